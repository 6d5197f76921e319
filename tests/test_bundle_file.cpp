// The edge bundle's HDF5 file: round trips, contiguous storage for memory-mapping, crash-safe
// rewrites and one-line errors for every kind of bad file; a BundleView of a file and of the
// same bundle in memory.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <random>
#include <regex>
#include <thread>

#include "lazyboe/bundle/bundle_file.h"
#include "lazyboe/bundle/bundle_format.h"
#include "lazyboe/bundle/bundle_view.h"
#include "lazyboe/bundle/hdf5_handle.h"
#include "lazyboe/common/atomic_file.h"
#include "lazyboe/common/error.h"
#include "lazyboe/common/hash.h"
#include "test_util.h"

namespace lazyboe {
namespace {

namespace fs = std::filesystem;
using test::random_bundle;
using test::temp_dir;
using test::viewable_bundle;

Bundle empty_bundle(int dof) {
  Bundle b;
  b.header.dof = dof;
  b.header.region_lower.assign(dof, -1.0);
  b.header.region_upper.assign(dof, 1.0);
  b.knot_offset = {0};
  b.sample_offset = {0};
  return b;
}

template <class T>
bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

void expect_same_header(const BundleHeader& a, const BundleHeader& b) {
  EXPECT_EQ(a.schema_version, b.schema_version);
  EXPECT_EQ(a.tool_version, b.tool_version);
  EXPECT_EQ(a.complete, b.complete);
  EXPECT_EQ(a.robot_name, b.robot_name);
  EXPECT_EQ(a.robot_config, b.robot_config);
  EXPECT_EQ(a.robot_hash, b.robot_hash);
  EXPECT_EQ(a.env_name, b.env_name);
  EXPECT_EQ(a.env_file, b.env_file);
  EXPECT_EQ(a.env_hash, b.env_hash);
  EXPECT_EQ(a.dof, b.dof);
  EXPECT_EQ(a.seed, b.seed);
  EXPECT_EQ(a.target_edges, b.target_edges);
  EXPECT_TRUE(same_bytes(a.region_lower, b.region_lower));
  EXPECT_TRUE(same_bytes(a.region_upper, b.region_upper));
  EXPECT_TRUE(same_bits(a.min_duration, b.min_duration));
  EXPECT_TRUE(same_bits(a.max_duration, b.max_duration));
  EXPECT_TRUE(same_bits(a.knot_interval, b.knot_interval));
  EXPECT_TRUE(same_bits(a.velocity_scale, b.velocity_scale));
  EXPECT_TRUE(same_bits(a.limit_scale, b.limit_scale));
  EXPECT_TRUE(same_bits(a.control_rate, b.control_rate));
  EXPECT_TRUE(same_bits(a.sample_interval, b.sample_interval));
  EXPECT_TRUE(same_bits(a.design_theta, b.design_theta));
  EXPECT_EQ(a.attempts, b.attempts);
  EXPECT_EQ(a.valid, b.valid);
  EXPECT_EQ(a.rejected, b.rejected);
  EXPECT_EQ(a.start_resamples, b.start_resamples);
  EXPECT_EQ(a.integrator, b.integrator);
  EXPECT_EQ(a.substeps, b.substeps);
  EXPECT_TRUE(same_bits(a.simulated_seconds, b.simulated_seconds));
  EXPECT_TRUE(same_bits(a.wall_seconds, b.wall_seconds));
}

void expect_same(const Bundle& a, const Bundle& b) {
  expect_same_header(a.header, b.header);
  EXPECT_TRUE(same_bytes(a.q0, b.q0));
  EXPECT_TRUE(same_bytes(a.qf, b.qf));
  EXPECT_TRUE(same_bytes(a.duration, b.duration));
  EXPECT_TRUE(same_bytes(a.command_duration, b.command_duration));
  EXPECT_TRUE(same_bytes(a.attempt, b.attempt));
  EXPECT_TRUE(same_bytes(a.knot_offset, b.knot_offset));
  EXPECT_TRUE(same_bytes(a.knots, b.knots));
  EXPECT_TRUE(same_bytes(a.sample_offset, b.sample_offset));
  EXPECT_TRUE(same_bytes(a.sample_q, b.sample_q));
  EXPECT_TRUE(same_bytes(a.sample_dq, b.sample_dq));
}

// The message of the Error f throws ("" and a test failure when it throws none).
std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an Error";
  return "";
}

// One line, starting with the file, mentioning every one of `parts`.
void expect_error(const std::string& message, const std::string& file,
                  std::initializer_list<std::string> parts) {
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  EXPECT_EQ(message.rfind(file + ": ", 0), 0u) << message;
  for (const std::string& part : parts) EXPECT_NE(message.find(part), std::string::npos) << message;
}

std::string fresh_path(const std::string& name) {
  const std::string dir = temp_dir() + "/" + name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir + "/bundle.h5";
}

// Files in the directory of `path` other than `path` itself (leftover temporaries).
std::vector<std::string> others_in_dir(const std::string& path) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(fs::path(path).parent_path()))
    if (e.path() != fs::path(path)) out.push_back(e.path().filename().string());
  return out;
}

std::string file_bytes(const std::string& path) { return test::read_file(path); }

// ---- hashes -------------------------------------------------------------------------------

TEST(Hash, Fnv1a64KnownValues) {
  EXPECT_EQ(fnv1a64_hex(""), "cbf29ce484222325");
  EXPECT_EQ(fnv1a64_hex("a"), "af63dc4c8601ec8c");
  EXPECT_EQ(fnv1a64_hex("foobar"), "85944171f73967e8");
}

// Jenkins' lookup3 test vectors (hashlittle), and HDF5's own checksum of a superblock.
TEST(Hash, Lookup3KnownValues) {
  EXPECT_EQ(lookup3("", 0, 0), 0xdeadbeefu);
  const std::string four = "Four score and seven years ago";
  EXPECT_EQ(lookup3(four.data(), four.size(), 0), 0x17770551u);
  EXPECT_EQ(lookup3(four.data(), four.size(), 1), 0xcd628161u);
  // A bundle's version 2 superblock: its last 4 bytes are the lookup3 of the 44 before them.
  const std::string path = fresh_path("superblock");
  write_bundle(path, random_bundle(2, 7, 3));
  const std::string bytes = file_bytes(path);
  ASSERT_GE(bytes.size(), 48u);
  ASSERT_EQ(bytes[8], 2);  // superblock version
  uint32_t stored = 0;
  for (int i = 3; i >= 0; --i) stored = stored << 8 | static_cast<unsigned char>(bytes[44 + i]);
  EXPECT_EQ(lookup3(bytes.data(), 44, 0), stored);
}

TEST(Hash, FilesAreLengthPrefixed) {
  const std::string a = test::write_temp_file("hash/a.txt", "ab");
  const std::string b = test::write_temp_file("hash/b.txt", "c");
  const std::string c = test::write_temp_file("hash/c.txt", "a");
  const std::string d = test::write_temp_file("hash/d.txt", "bc");
  const std::string len2("\x02\0\0\0\0\0\0\0", 8), len1("\x01\0\0\0\0\0\0\0", 8);
  EXPECT_EQ(hash_files({a, b}), fnv1a64_hex(len2 + "ab" + len1 + "c"));
  EXPECT_NE(hash_files({a, b}), hash_files({c, d}));  // same concatenation, other split
  EXPECT_EQ(hash_files({}), fnv1a64_hex(""));
  const std::string missing = temp_dir() + "/hash/missing.urdf";
  expect_error(error_of([&] { hash_files({a, missing}); }), missing, {"cannot read"});
}

// ---- round trips --------------------------------------------------------------------------

TEST(BundleFile, RandomBundleRoundTripIsBitIdentical) {
  const Bundle b = random_bundle(50, 7, 42);
  ASSERT_GT(b.knots.size(), 0u);
  ASSERT_NE(b.knot_offset.back(), b.sample_offset.back());
  const std::string path = fresh_path("roundtrip");
  write_bundle(path, b);
  const Bundle r = read_bundle(path);
  expect_same(b, r);
  EXPECT_EQ(r.size(), 50u);
  EXPECT_TRUE(std::signbit(r.knots[0]));

  uint64_t edges = 0;
  const BundleHeader h = read_bundle_header(path, &edges);
  expect_same_header(b.header, h);
  EXPECT_EQ(edges, 50u);
  EXPECT_TRUE(others_in_dir(path).empty());
}

TEST(BundleFile, EmptyBundleRoundTrip) {
  const Bundle b = empty_bundle(7);
  const std::string path = fresh_path("empty");
  write_bundle(path, b);
  const Bundle r = read_bundle(path);
  expect_same(b, r);
  EXPECT_EQ(r.size(), 0u);
  EXPECT_FALSE(r.header.complete);
  EXPECT_TRUE(r.header.rejected.empty());
  for (const char* name : {bundle_dataset::q0, bundle_dataset::knots, bundle_dataset::sample_dq}) {
    const DatasetLocation loc = dataset_location(path, name);
    EXPECT_TRUE(loc.contiguous) << name;
    EXPECT_EQ(loc.bytes, 0u) << name;
  }
}

TEST(BundleFile, SameBundleGivesSameBytes) {
  const Bundle b = random_bundle(20, 7, 5);
  const std::string p1 = fresh_path("same1"), p2 = fresh_path("same2");
  write_bundle(p1, b);
  write_bundle(p2, b);
  EXPECT_EQ(file_bytes(p1), file_bytes(p2));
}

TEST(BundleFile, RewriteReplacesTheFile) {
  const std::string path = fresh_path("rewrite");
  write_bundle(path, random_bundle(10, 7, 1));
  const Bundle b = random_bundle(30, 7, 2);
  write_bundle(path, b);
  expect_same(b, read_bundle(path));
  EXPECT_TRUE(others_in_dir(path).empty());
}

// ---- memory-mapping -----------------------------------------------------------------------

template <class T>
void expect_mapped(const std::string& path, int fd, const char* name, const std::vector<T>& data) {
  const DatasetLocation loc = dataset_location(path, name);
  EXPECT_TRUE(loc.contiguous) << name;
  ASSERT_EQ(loc.bytes, data.size() * sizeof(T)) << name;
  std::vector<T> raw(data.size());
  ASSERT_EQ(::pread(fd, raw.data(), loc.bytes, static_cast<off_t>(loc.file_offset)),
            static_cast<ssize_t>(loc.bytes))
      << name;
  EXPECT_TRUE(same_bytes(raw, data)) << name;
}

TEST(BundleFile, DatasetsAreContiguousAndMappable) {
  const Bundle b = random_bundle(50, 7, 7);
  const std::string path = fresh_path("mapped");
  write_bundle(path, b);
  const int fd = ::open(path.c_str(), O_RDONLY);
  ASSERT_GE(fd, 0);
  namespace ds = bundle_dataset;
  expect_mapped(path, fd, ds::q0, b.q0);
  expect_mapped(path, fd, ds::qf, b.qf);
  expect_mapped(path, fd, ds::duration, b.duration);
  expect_mapped(path, fd, ds::command_duration, b.command_duration);
  expect_mapped(path, fd, ds::attempt, b.attempt);
  expect_mapped(path, fd, ds::knot_offset, b.knot_offset);
  expect_mapped(path, fd, ds::sample_offset, b.sample_offset);
  expect_mapped(path, fd, ds::knots, b.knots);
  expect_mapped(path, fd, ds::sample_q, b.sample_q);
  expect_mapped(path, fd, ds::sample_dq, b.sample_dq);
  ::close(fd);
  expect_error(error_of([&] { dataset_location(path, "/edges/nope"); }), path,
               {"/edges/nope", "missing"});
}

// ---- crash safety -------------------------------------------------------------------------

TEST(BundleFile, FailedWriteKeepsTheOldFile) {
  const std::string path = fresh_path("failed");
  const Bundle old = random_bundle(25, 7, 3);
  write_bundle(path, old);

  Bundle bad = random_bundle(40, 7, 4);
  bad.qf.pop_back();
  expect_error(error_of([&] { write_bundle(path, bad); }), path, {"bundle.qf", "279", "280"});
  expect_same(old, read_bundle(path));
  EXPECT_TRUE(others_in_dir(path).empty());

  // A failure after the temporary file is under way: something is in the way of its name.
  const std::string tmp = next_temporary_name(path);
  fs::create_directory(tmp);
  expect_error(error_of([&] { write_bundle(path, random_bundle(40, 7, 4)); }), path,
               {"cannot write", "Is a directory"});
  expect_same(old, read_bundle(path));
  EXPECT_TRUE(fs::is_directory(tmp));  // not ours to remove
  fs::remove(tmp);
  EXPECT_TRUE(others_in_dir(path).empty());
}

TEST(BundleFile, InconsistentBundlesAreRefusedNamingTheField) {
  const std::string path = fresh_path("inconsistent");
  const Bundle good = random_bundle(10, 7, 9);
  struct Case {
    std::function<void(Bundle&)> spoil;
    std::vector<std::string> parts;
  };
  const std::vector<Case> cases = {
      {[](Bundle& b) { b.header.dof = 0; }, {"bundle.header.dof"}},
      {[](Bundle& b) { b.header.schema_version = 2; }, {"bundle.header.schema_version"}},
      {[](Bundle& b) { b.header.region_upper.pop_back(); }, {"bundle.header.region_upper", "6"}},
      {[](Bundle& b) { b.q0.push_back(1); }, {"bundle.q0", "71", "70"}},
      {[](Bundle& b) { b.command_duration.pop_back(); }, {"bundle.command_duration"}},
      {[](Bundle& b) { b.attempt.clear(); }, {"bundle.attempt"}},
      {[](Bundle& b) { b.knot_offset.pop_back(); }, {"bundle.knot_offset", "edges + 1"}},
      {[](Bundle& b) { b.sample_offset[0] = 1; }, {"bundle.sample_offset", "first value"}},
      {[](Bundle& b) { b.knot_offset.back() += 1; },
       {"bundle.knot_offset", "last value", "bundle.knots"}},
      {[](Bundle& b) { std::swap(b.sample_offset[3], b.sample_offset[4]); },
       {"bundle.sample_offset", "decreases at edge 3"}},
      {[](Bundle& b) { b.knots.pop_back(); }, {"bundle.knots", "multiple of dof"}},
      {[](Bundle& b) { b.sample_dq.pop_back(); }, {"bundle.sample_dq"}},
  };
  for (const Case& c : cases) {
    Bundle b = good;
    c.spoil(b);
    const std::string message = error_of([&] { write_bundle(path, b); });
    expect_error(message, path, {});
    for (const std::string& part : c.parts)
      EXPECT_NE(message.find(part), std::string::npos) << message;
    EXPECT_FALSE(fs::exists(path));
    EXPECT_TRUE(others_in_dir(path).empty());
  }
}

// A writer killed at arbitrary moments leaves either the old or the new file, never a broken one.
TEST(BundleFile, KilledWriterLeavesACompleteFile) {
  const std::string path = fresh_path("killed");
  const Bundle a = random_bundle(3000, 7, 11), b = random_bundle(2000, 7, 12);
  // Kill after 0.25 to 3 times the time one write takes here, so some kills land mid-write and
  // some after the new file is in place, on fast and slow disks alike.
  const auto start = std::chrono::steady_clock::now();
  write_bundle(path, b);
  const auto one_write = std::chrono::steady_clock::now() - start;
  write_bundle(path, a);
  int saw_b = 0;
  for (int round = 0; round < 12; ++round) {
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      try {
        for (int i = 0;; ++i) write_bundle(path, i % 2 ? a : b);
      } catch (...) {
        ::_exit(1);
      }
    }
    std::this_thread::sleep_for(one_write * (round + 1) / 4);
    ::kill(child, SIGKILL);
    int status = 0;
    ::waitpid(child, &status, 0);
    ASSERT_TRUE(WIFSIGNALED(status)) << "the writer failed on its own";
    const Bundle r = read_bundle(path);
    ASSERT_TRUE(r.header.seed == a.header.seed || r.header.seed == b.header.seed);
    if (r.header.seed == a.header.seed) {
      expect_same(a, r);
    } else {
      expect_same(b, r);
      ++saw_b;
    }
    // A killed writer cannot remove its temporary file; only such files may be left.
    for (const std::string& name : others_in_dir(path)) {
      EXPECT_EQ(name.rfind("bundle.h5.tmp.", 0), 0u) << name;
      fs::remove(fs::path(path).parent_path() / name);
    }
  }
  EXPECT_GT(saw_b, 0) << "the writer never got a file in place; kill later";
}

// ---- bad files ----------------------------------------------------------------------------

TEST(BundleFile, MissingFile) {
  const std::string path = temp_dir() + "/no/such/bundle.h5";
  expect_error(error_of([&] { read_bundle(path); }), path, {"No such file"});
  expect_error(error_of([&] { read_bundle_header(path); }), path, {"No such file"});
}

TEST(BundleFile, NotAnHdf5File) {
  const std::string path = test::write_temp_file("text.h5", "q0,qf\n1,2\n");
  expect_error(error_of([&] { read_bundle(path); }), path, {"not an HDF5 file"});
}

TEST(BundleFile, OtherSchemaVersions) {
  for (int version : {2, 0}) {
    const std::string path = fresh_path("version" + std::to_string(version));
    {
      h5::File file(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT));
      ASSERT_TRUE(file.valid());
      h5::Dataspace space(H5Screate(H5S_SCALAR));
      h5::Attribute attr(
          H5Acreate2(file, "schema_version", H5T_STD_I32LE, space, H5P_DEFAULT, H5P_DEFAULT));
      ASSERT_TRUE(attr.valid());
      ASSERT_GE(H5Awrite(attr, H5T_NATIVE_INT, &version), 0);
    }
    const std::string message = error_of([&] { read_bundle(path); });
    expect_error(message, path,
                 {"schema_version " + std::to_string(version),
                  version > 1 ? "newer lazyboe" : "older lazyboe"});
    EXPECT_EQ(error_of([&] { read_bundle_header(path); }), message);
  }
}

// Damaged files give our one line and nothing from HDF5 on stderr, in any thread.
TEST(BundleFile, TruncatedFileQuietly) {
  const std::string path = fresh_path("truncated");
  write_bundle(path, random_bundle(50, 7, 13));
  const std::string bytes = file_bytes(path);
  fs::resize_file(path, bytes.size() / 2);
  testing::internal::CaptureStderr();
  std::string message, thread_message;
  message = error_of([&] { read_bundle(path); });
  std::thread([&] { thread_message = error_of([&] { read_bundle(path); }); }).join();
  const std::string err = testing::internal::GetCapturedStderr();
  expect_error(message, path, {"cannot open as an HDF5 file"});
  EXPECT_EQ(thread_message, message);
  EXPECT_EQ(err, "");
}

// Strings are stored in the object headers (fixed length), not in a global heap, which HDF5
// 1.10 reads without bounds checks.
TEST(BundleFile, StringAttributesAreFixedLength) {
  const std::string path = fresh_path("strings");
  write_bundle(path, random_bundle(3, 7, 5));
  h5::File file = h5::open_file(path);
  for (const char* name : {"tool_version", "robot_name", "rejected_reasons", "integrator"}) {
    h5::Attribute attr(H5Aopen(file, name, H5P_DEFAULT));
    ASSERT_TRUE(attr.valid()) << name;
    h5::Datatype type(H5Aget_type(attr));
    EXPECT_EQ(H5Tget_class(type), H5T_STRING) << name;
    EXPECT_EQ(H5Tis_variable_str(type), 0) << name;
  }
  EXPECT_EQ(file_bytes(path).find("GCOL"), std::string::npos);  // no global heap at all
}

// A bundle input of the fuzz target (tests/fuzz/fuzz_bundle.cpp) as a file: its first byte
// chose the reader, the rest is the file.
std::string regression_bundle(const std::string& name) {
  const std::string bytes =
      file_bytes(test::source_path("tests/fuzz/regressions/bundle/" + name + ".h5"));
  const std::string path = fresh_path(name);
  std::ofstream(path, std::ios::binary) << bytes.substr(1);
  return path;
}

// Bundles written with variable-length strings (before the change above) still open.
TEST(BundleFile, OlderFileWithVariableLengthStringsOpens) {
  const std::string path = regression_bundle("old-format-b1p");
  const Bundle b = read_bundle(path);
  EXPECT_EQ(b.header.robot_name, "panda");
  EXPECT_EQ(b.size(), 1u);
  EXPECT_EQ(BundleView::open(path).size(), 1u);
}

// Found by fuzzing (tests/fuzz/regressions/bundle/global-heap-object-past-its-collection.h5):
// an older bundle whose global heap says an object is larger than the heap made HDF5 1.10 copy
// far past it (a crash at the first string attribute). Now one line naming the file.
TEST(BundleFile, DamagedGlobalHeapOfAnOlderFileIsRefused) {
  const std::string path = regression_bundle("global-heap-object-past-its-collection");
  for (const auto& open : std::vector<std::function<void()>>{
           [&] { read_bundle(path); }, [&] { read_bundle_header(path); },
           [&] { BundleView::open(path); }, [&] { BundleView::open(path, false); }}) {
    expect_error(error_of(open), path, {"global heap", "runs past its end"});
  }
}

TEST(BundleFile, PlainHdf5FileIsNotABundle) {
  const std::string path = fresh_path("plain");
  { h5::File file = h5::create_file(path); }
  expect_error(error_of([&] { read_bundle(path); }), path, {"schema_version missing"});
}

// Writes a good bundle, then damages it with the C API.
std::string damaged(const std::string& name, const std::function<void(hid_t)>& damage) {
  const std::string path = fresh_path(name);
  write_bundle(path, random_bundle(50, 7, 21));
  h5::File file = h5::open_file_rw(path);
  damage(file);
  h5::close_file(path, file);
  return path;
}

TEST(BundleFile, MissingDataset) {
  const std::string path =
      damaged("noqf", [](hid_t f) { ASSERT_GE(H5Ldelete(f, "/edges/qf", H5P_DEFAULT), 0); });
  expect_error(error_of([&] { read_bundle(path); }), path, {"/edges/qf", "missing"});
  read_bundle_header(path);  // the header alone is still fine
}

TEST(BundleFile, MissingAttribute) {
  const std::string path =
      damaged("noattr", [](hid_t f) { ASSERT_GE(H5Adelete(f, "design_theta"), 0); });
  expect_error(error_of([&] { read_bundle_header(path); }), path,
               {"attribute design_theta missing"});
}

TEST(BundleFile, WrongShape) {
  const std::string path = damaged("shape", [](hid_t f) {
    ASSERT_GE(H5Ldelete(f, "/edges/q0", H5P_DEFAULT), 0);
    h5::write_dataset<double>("x", f, "/edges/q0", std::vector<double>(50 * 6), {50, 6});
  });
  expect_error(error_of([&] { read_bundle(path); }), path,
               {"/edges/q0", "shape 50 x 6, expected 50 x 7"});
}

TEST(BundleFile, WrongType) {
  const std::string path = damaged("type", [](hid_t f) {
    ASSERT_GE(H5Ldelete(f, "/edges/duration", H5P_DEFAULT), 0);
    h5::write_dataset<float>("x", f, "/edges/duration", std::vector<float>(50), {50});
  });
  expect_error(error_of([&] { read_bundle(path); }), path,
               {"/edges/duration", "float32", "float64"});
}

void set_last_offset(hid_t f, const char* name, uint64_t delta, bool decrease_middle = false) {
  std::vector<uint64_t> off = h5::read_dataset<uint64_t>("x", f, name, {51});
  off.back() += delta;
  if (decrease_middle) off[10] = off[11] + 1;
  h5::Dataset d(H5Dopen2(f, name, H5P_DEFAULT));
  ASSERT_GE(H5Dwrite(d, H5T_NATIVE_UINT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, off.data()), 0);
}

TEST(BundleFile, KnotOffsetDisagreesWithKnots) {
  const std::string path =
      damaged("knots", [](hid_t f) { set_last_offset(f, "/edges/knot_offset", 1); });
  expect_error(error_of([&] { read_bundle(path); }), path,
               {"/edges/knot_offset", "last value", "/controls/knots"});
}

TEST(BundleFile, SampleOffsetDecreases) {
  const std::string path =
      damaged("samples", [](hid_t f) { set_last_offset(f, "/edges/sample_offset", 0, true); });
  expect_error(error_of([&] { read_bundle(path); }), path,
               {"/edges/sample_offset", "decreases at edge 10"});
}

TEST(BundleFile, RejectedAttributesMustPair) {
  const std::string path = damaged("rejected", [](hid_t f) {
    h5::write_attr_u64s("x", f, "rejected_counts", {1, 2});
  });
  expect_error(error_of([&] { read_bundle_header(path); }), path,
               {"rejected_counts", "rejected_reasons"});
}

// ---- BundleView from a file and from memory -------------------------------------------------

// Adds the transfer statistics to a bundle's perturbation analysis (viewable_bundle has none,
// like an analysis written before them).
void add_transfer(Bundle& b, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 0.01);
  Perturbation& p = b.perturbation;
  p.has_transfer = true;
  for (size_t k = 0; k < b.size(); ++k) {
    const uint64_t lazy = p.valid[k] - p.valid[k] / 3;
    p.transfer_lazy.push_back(lazy);
    p.transfer_max_error.push_back(p.valid[k] ? u(rng) : std::nan(""));
    p.p_lazy_prop_transfer.push_back(p.valid[k] ? static_cast<double>(lazy) / p.valid[k] : 0.0);
  }
}

Bundle viewable_bundle_with_transfer(size_t n, int dof, uint64_t seed) {
  Bundle b = viewable_bundle(n, dof, seed);
  add_transfer(b, seed + 2);
  return b;
}

// The first edge (and what) on which two views differ; "" when they agree bit for bit.
std::string view_difference(const BundleView& a, const BundleView& b) {
  if (a.size() != b.size()) return "size";
  if (a.dof() != b.dof()) return "dof";
  if (a.has_perturbation() != b.has_perturbation()) return "has_perturbation";
  if (!same_bits(a.perturbation_theta(), b.perturbation_theta())) return "perturbation_theta";
  if (a.has_transfer() != b.has_transfer()) return "has_transfer";
  const size_t n = static_cast<size_t>(a.dof());
  for (size_t e = 0; e < a.size(); ++e) {
    const std::string at = " of edge " + std::to_string(e);
    if (std::memcmp(a.q0(e), b.q0(e), n * sizeof(double)) != 0) return "q0" + at;
    if (std::memcmp(a.qf(e), b.qf(e), n * sizeof(double)) != 0) return "qf" + at;
    if (!same_bits(a.duration(e), b.duration(e))) return "duration" + at;
    const CommandProfile ca = a.command(e), cb = b.command(e);
    if (ca.n_knots != cb.n_knots || ca.dof != cb.dof || !same_bits(ca.duration, cb.duration) ||
        std::memcmp(ca.knots, cb.knots, ca.n_knots * n * sizeof(double)) != 0) {
      return "command" + at;
    }
    if (a.has_perturbation()) {
      if (!same_bits(a.p_lazy_prop(e), b.p_lazy_prop(e))) return "p_lazy_prop" + at;
      if (!same_bits(a.p_collision(e), b.p_collision(e))) return "p_collision" + at;
    }
    if (a.has_transfer()) {
      if (!same_bits(a.p_lazy_prop_transfer(e), b.p_lazy_prop_transfer(e)))
        return "p_lazy_prop_transfer" + at;
      if (!same_bits(a.transfer_max_error(e), b.transfer_max_error(e)))
        return "transfer_max_error" + at;
    }
  }
  return "";
}

TEST(BundleView, FromMemoryEqualsTheSameBundleOpenedFromItsFile) {
  const auto bundle = std::make_shared<const Bundle>(viewable_bundle(40, 7, 11));
  const std::string path = fresh_path("view-memory");
  write_bundle(path, *bundle);
  const BundleView mapped = BundleView::open(path, true);
  const BundleView read = BundleView::open(path, false);
  const BundleView memory = BundleView::from_memory(bundle, "in-memory test bundle");
  EXPECT_EQ(memory.path(), "in-memory test bundle");
  EXPECT_FALSE(memory.memory_mapped());
  EXPECT_TRUE(memory.warnings().empty());
  ASSERT_EQ(memory.size(), 40u);
  ASSERT_TRUE(memory.has_perturbation());
  EXPECT_EQ(view_difference(mapped, memory), "");
  EXPECT_EQ(view_difference(read, memory), "");
  expect_same_header(mapped.header(), memory.header());
  // A view into the bundle's own arrays, kept alive by the view alone.
  EXPECT_EQ(memory.q0(0), bundle->q0.data());
  std::weak_ptr<const Bundle> watch;
  std::unique_ptr<BundleView> only;
  {
    const auto copy = std::make_shared<const Bundle>(*bundle);
    watch = copy;
    only = std::make_unique<BundleView>(BundleView::from_memory(copy, "copy"));
  }
  EXPECT_FALSE(watch.expired());
  EXPECT_EQ(view_difference(*only, memory), "");
  only.reset();
  EXPECT_TRUE(watch.expired());
}

TEST(BundleView, FromMemoryUsesOnlyAFinishedPerturbationAsOpenDoes) {
  Bundle b = viewable_bundle(10, 7, 12);
  b.perturbation.complete = false;
  const std::string path = fresh_path("view-unfinished");
  write_bundle(path, b);
  const BundleView file = BundleView::open(path);
  const BundleView memory =
      BundleView::from_memory(std::make_shared<const Bundle>(b), "unfinished analysis");
  EXPECT_FALSE(file.has_perturbation());
  EXPECT_FALSE(memory.has_perturbation());
  EXPECT_EQ(memory.warnings(), file.warnings());
  EXPECT_EQ(view_difference(file, memory), "");
  b.perturbation = Perturbation{};
  EXPECT_FALSE(
      BundleView::from_memory(std::make_shared<const Bundle>(b), "none").has_perturbation());
}

TEST(BundleView, FromMemoryRefusesIncompleteAndInconsistentBundles) {
  const Bundle good = viewable_bundle(10, 7, 13);
  ASSERT_NO_THROW(BundleView::from_memory(std::make_shared<const Bundle>(good), "good"));
  const std::string name = "spoilt in-memory bundle";
  struct Case {
    std::function<void(Bundle&)> spoil;
    std::vector<std::string> parts;
  };
  const std::vector<Case> cases = {
      {[](Bundle& b) { b.header.complete = false; }, {"incomplete bundle", "--resume"}},
      {[](Bundle& b) { b.header.dof = 0; }, {"bundle.header.dof"}},
      {[](Bundle& b) { b.header.schema_version = 2; }, {"bundle.header.schema_version"}},
      {[](Bundle& b) { b.q0.push_back(1); }, {"bundle.q0", "71", "70"}},
      {[](Bundle& b) { b.duration.pop_back(); }, {"bundle.q0"}},
      {[](Bundle& b) { b.knot_offset.pop_back(); }, {"bundle.knot_offset", "edges + 1"}},
      {[](Bundle& b) { b.knot_offset.back() += 1; },
       {"bundle.knot_offset", "last value", "bundle.knots"}},
      {[](Bundle& b) { b.knots.pop_back(); }, {"bundle.knots", "multiple of dof"}},
      {[](Bundle& b) { b.perturbation.p_lazy_prop.pop_back(); },
       {"bundle.perturbation.p_lazy_prop"}},
      {[](Bundle& b) { b.perturbation.p_collision.push_back(0); },
       {"bundle.perturbation.p_collision"}},
      {[](Bundle& b) {
         add_transfer(b, 1);
         b.perturbation.transfer_lazy.pop_back();
       },
       {"bundle.perturbation.transfer_lazy", "9", "10"}},
      {[](Bundle& b) {
         add_transfer(b, 1);
         b.perturbation.transfer_max_error.push_back(0);
       },
       {"bundle.perturbation.transfer_max_error", "11", "10"}},
      {[](Bundle& b) {
         add_transfer(b, 1);
         b.perturbation.p_lazy_prop_transfer.clear();
       },
       {"bundle.perturbation.p_lazy_prop_transfer"}},
      {[](Bundle& b) {
         b.perturbation.has_transfer = true;  // flagged, with no arrays
       },
       {"bundle.perturbation.transfer_lazy"}},
      // Consistent for check_bundle, but an edge of one knot is no command.
      {[](Bundle& b) {
         b.knot_offset[1] = 1;
         for (size_t k = 0; k < 7; ++k) b.knots.erase(b.knots.begin());
         for (size_t e = 2; e < b.knot_offset.size(); ++e) b.knot_offset[e] -= 1;
       },
       {"knot_offset", "edge 0", "bad knot range"}},
  };
  for (const Case& c : cases) {
    Bundle b = good;
    c.spoil(b);
    const std::string message =
        error_of([&] { BundleView::from_memory(std::make_shared<const Bundle>(b), name); });
    expect_error(message, name, {});
    for (const std::string& part : c.parts)
      EXPECT_NE(message.find(part), std::string::npos) << message;
  }
  expect_error(error_of([&] { BundleView::from_memory(nullptr, name); }), name, {"no bundle"});
}

// ---- the transfer statistics: optional datasets of /perturbation ----------------------------

// Bit-for-bit equality of two arrays (NaN equal to the same NaN).
template <typename T>
bool same_values(const char*, const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

void expect_same_transfer(const Perturbation& a, const Perturbation& b) {
  EXPECT_EQ(a.has_transfer, b.has_transfer);
  EXPECT_TRUE(same_values("transfer_lazy", a.transfer_lazy, b.transfer_lazy));
  EXPECT_TRUE(same_values("transfer_max_error", a.transfer_max_error, b.transfer_max_error));
  EXPECT_TRUE(same_values("p_lazy_prop_transfer", a.p_lazy_prop_transfer, b.p_lazy_prop_transfer));
  EXPECT_TRUE(same_values("p_lazy_prop", a.p_lazy_prop, b.p_lazy_prop));
  EXPECT_TRUE(same_values("max_error", a.max_error, b.max_error));
}

TEST(BundleFile, TransferStatisticsRoundTripBitIdentical) {
  const Bundle b = viewable_bundle_with_transfer(30, 7, 14);
  const std::string path = fresh_path("transfer");
  write_bundle(path, b);
  const Bundle r = read_bundle(path);
  ASSERT_TRUE(r.perturbation.has_transfer);
  expect_same_transfer(b.perturbation, r.perturbation);
  {
    h5::File file = h5::open_file(path);
    for (const char* name : {bundle_dataset::transfer_lazy, bundle_dataset::transfer_max_error,
                             bundle_dataset::p_lazy_prop_transfer}) {
      EXPECT_EQ(h5::dataset_shape(path, file, name), std::vector<uint64_t>{30}) << name;
      const DatasetLocation loc = dataset_location(path, file, name);
      EXPECT_TRUE(loc.contiguous) << name;
      EXPECT_EQ(loc.bytes, 30 * 8u) << name;
    }
  }
  const BundleView mapped = BundleView::open(path, true), read = BundleView::open(path, false);
  const BundleView memory = BundleView::from_memory(std::make_shared<const Bundle>(b), "memory");
  EXPECT_TRUE(mapped.memory_mapped());
  ASSERT_TRUE(mapped.has_transfer());
  ASSERT_TRUE(memory.has_transfer());
  EXPECT_EQ(view_difference(mapped, memory), "");
  EXPECT_EQ(view_difference(read, memory), "");
  EXPECT_EQ(mapped.p_lazy_prop_transfer(3), b.perturbation.p_lazy_prop_transfer[3]);
}

// A bundle written before the transfer statistics (its /perturbation without them) opens
// everywhere, without them.
TEST(BundleFile, AnalysisWithoutTransferStatisticsStillOpens) {
  const Bundle b = viewable_bundle(20, 7, 15);
  ASSERT_FALSE(b.perturbation.has_transfer);
  const std::string path = fresh_path("no-transfer");
  write_bundle(path, b);
  {
    h5::File file = h5::open_file(path);
    EXPECT_TRUE(h5::exists(file, bundle_dataset::p_lazy_prop));
    EXPECT_FALSE(h5::exists(file, bundle_dataset::transfer_lazy));
    EXPECT_FALSE(h5::exists(file, bundle_dataset::transfer_max_error));
    EXPECT_FALSE(h5::exists(file, bundle_dataset::p_lazy_prop_transfer));
  }
  const Bundle r = read_bundle(path);
  EXPECT_TRUE(r.perturbation.present);
  EXPECT_FALSE(r.perturbation.has_transfer);
  EXPECT_TRUE(r.perturbation.transfer_lazy.empty());
  expect_same_transfer(b.perturbation, r.perturbation);
  const BundleView view = BundleView::open(path);
  EXPECT_TRUE(view.has_perturbation());
  EXPECT_FALSE(view.has_transfer());
  EXPECT_TRUE(view.warnings().empty());
  const BundleView memory = BundleView::from_memory(std::make_shared<const Bundle>(b), "memory");
  EXPECT_FALSE(memory.has_transfer());
  EXPECT_EQ(view_difference(view, memory), "");
}

// The three come together: a file holding only some of them is refused, naming the missing one;
// a wrong shape is refused as for every dataset.
TEST(BundleFile, PartialOrMisshapenTransferStatisticsAreRefused) {
  const std::string path = fresh_path("transfer-partial");
  write_bundle(path, viewable_bundle_with_transfer(20, 7, 16));
  {
    h5::File file = h5::open_file_rw(path);
    ASSERT_GE(H5Ldelete(file, bundle_dataset::transfer_max_error, H5P_DEFAULT), 0);
    h5::close_file(path, file);
  }
  expect_error(error_of([&] { read_bundle(path); }), path,
               {"/perturbation/transfer_max_error", "missing"});
  const std::string shape = fresh_path("transfer-shape");
  write_bundle(shape, viewable_bundle_with_transfer(20, 7, 16));
  {
    h5::File file = h5::open_file_rw(shape);
    ASSERT_GE(H5Ldelete(file, bundle_dataset::transfer_lazy, H5P_DEFAULT), 0);
    h5::write_dataset<uint64_t>("x", file, bundle_dataset::transfer_lazy, std::vector<uint64_t>(19),
                                {19});
    h5::close_file(shape, file);
  }
  expect_error(error_of([&] { read_bundle(shape); }), shape,
               {"/perturbation/transfer_lazy", "19", "20"});
}

TEST(BundleFile, WriterRefusesWrongSizesOfTheTransferStatistics) {
  const std::string path = fresh_path("transfer-sizes");
  const Bundle good = viewable_bundle_with_transfer(10, 7, 17);
  const std::vector<std::pair<std::function<void(Perturbation&)>, std::string>> cases = {
      {[](Perturbation& p) { p.transfer_lazy.pop_back(); }, "bundle.perturbation.transfer_lazy"},
      {[](Perturbation& p) { p.transfer_max_error.push_back(1); },
       "bundle.perturbation.transfer_max_error"},
      {[](Perturbation& p) { p.p_lazy_prop_transfer.clear(); },
       "bundle.perturbation.p_lazy_prop_transfer"},
  };
  for (const auto& [spoil, field] : cases) {
    Bundle b = good;
    spoil(b.perturbation);
    const std::string message = error_of([&] { write_bundle(path, b); });
    expect_error(message, path, {field});
    EXPECT_FALSE(fs::exists(path));
  }
}

// The format described once: schemas/bundle.md's dataset tables list the library's table
// (bundle_format.h) in its order, with the same shape, type and group.
TEST(BundleFormat, SchemaDocumentListsTheDatasetTable) {
  std::ifstream in(test::source_path("schemas/bundle.md"));
  ASSERT_TRUE(in) << "schemas/bundle.md";
  const std::regex row(R"(^\| `(/[a-z0-9_/]+)` \| ([^|]+) \| (\w+) \|)");
  std::vector<std::array<std::string, 3>> documented;
  for (std::string line; std::getline(in, line);) {
    std::smatch m;
    if (std::regex_search(line, m, row)) documented.push_back({m[1], m[2], m[3]});
  }
  const auto& table = bundle_datasets();
  ASSERT_EQ(documented.size(), table.size());
  for (size_t i = 0; i < table.size(); ++i) {
    const BundleDatasetSpec& spec = table[i];
    EXPECT_EQ(static_cast<size_t>(spec.id), i);
    EXPECT_EQ(documented[i][0], spec.path);
    EXPECT_EQ(documented[i][1], shape_rule_text(spec)) << spec.path;
    EXPECT_EQ(documented[i][2], element_type_name(spec.type)) << spec.path;
    const bool in_group = std::string(spec.path).rfind("/perturbation/", 0) == 0;
    EXPECT_EQ(in_group, spec.presence != Presence::Always) << spec.path;
  }
}

// A written bundle with every group holds every dataset of the table with the table's shape,
// each with a verified checksum, in the table's order.
TEST(BundleFormat, WrittenFilesFollowTheTable) {
  const std::string path = fresh_path("format");
  const Bundle b = viewable_bundle_with_transfer(12, 7, 21);
  write_bundle(path, b);
  const std::vector<DatasetVerification> verified = verify_bundle_checksums(path);
  ASSERT_EQ(verified.size(), kBundleDatasetCount);
  h5::File file = h5::open_file(path);
  const BundleRows rows{b.size(), b.knots.size() / 7, b.sample_q.size() / 7};
  for (const BundleDatasetSpec& spec : bundle_datasets()) {
    EXPECT_EQ(verified[static_cast<size_t>(spec.id)].dataset, spec.path);
    EXPECT_EQ(verified[static_cast<size_t>(spec.id)].status, DatasetVerification::Status::Verified);
    EXPECT_EQ(h5::dataset_shape(path, file, spec.path), dataset_shape(spec, rows, 7)) << spec.path;
  }
  // Without an analysis, only the datasets always there.
  const std::string plain = fresh_path("format-plain");
  write_bundle(plain, random_bundle(12, 7, 22));
  size_t always = 0;
  for (const BundleDatasetSpec& spec : bundle_datasets())
    always += spec.presence == Presence::Always;
  EXPECT_EQ(verify_bundle_checksums(plain).size(), always);
}

}  // namespace
}  // namespace lazyboe
