// FNV-1a 64-bit content hashes, written as 16 lowercase hex digits. They identify the inputs a
// bundle was built from (robot config + URDF, environment), not a security measure.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace lazyboe {

// A 64-bit key of several values, for hash tables in memory (joint-space cells and states):
// start from kKeySeed and mix each value in. Not a content hash; it may change between versions.
constexpr uint64_t kKeySeed = 0x9E3779B97F4A7C15ULL;
inline uint64_t mix_key(uint64_t h, uint64_t value) {
  h ^= value + 0x9E3779B97F4A7C15ULL + (h << 6) + (h >> 2);
  h *= 0xBF58476D1CE4E5B9ULL;
  return h ^ (h >> 31);
}

// Incremental FNV-1a 64 (offset basis 0xcbf29ce484222325, prime 0x100000001b3).
class Fnv1a64 {
 public:
  void update(const void* data, size_t size);
  void update(const std::string& bytes) { update(bytes.data(), bytes.size()); }
  uint64_t value() const { return h_; }
  std::string hex() const;

 private:
  uint64_t h_ = 0xcbf29ce484222325ull;
};

std::string to_hex64(uint64_t value);  // 16 lowercase hex digits

// FNV-1a 64 of the bytes, as 16 lowercase hex digits ("cbf29ce484222325" for "").
std::string fnv1a64_hex(const std::string& bytes);

// FNV-1a 64 over the files in order, each file's content preceded by its byte length as
// 8 bytes little-endian (so moving bytes from one file to the next changes the hash).
// An unreadable file throws Error naming it.
std::string hash_files(const std::vector<std::string>& paths);

// Bob Jenkins' lookup3 hash ("hashlittle", byte by byte), the checksum HDF5 puts on its
// metadata (written here from the published algorithm, for hdf5_handle's superblock repair).
uint32_t lookup3(const void* data, size_t size, uint32_t initval);

}  // namespace lazyboe
