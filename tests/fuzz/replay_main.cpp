// The ordinary build's driver for a fuzz target (ctest, no libFuzzer): runs
// LLVMFuzzerTestOneInput on every file of the target's corpus, then on seeded mutations of them
// for a few seconds, and on every file of the REPLAY_DIRs (the inputs of past findings, replayed
// as they are), so that a regression on any of them is caught by the ordinary suite. The mutations
// are a fixed sequence for a seed (bit flips, byte changes, inserted tokens, cut and duplicated
// ranges, splices of two files); how far into it a run gets depends on the time given.
//   usage: fuzz_<target> CORPUS_DIR [SECONDS [SEED [REPLAY_DIR...]]]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "fuzz_util.h"

namespace fs = std::filesystem;
using Bytes = std::vector<uint8_t>;

namespace {

std::vector<Bytes> read_corpus(const std::string& dir, std::vector<std::string>& names) {
  names.clear();
  for (const auto& entry : fs::directory_iterator(dir))
    if (entry.is_regular_file()) names.push_back(entry.path().string());
  std::sort(names.begin(), names.end());
  std::vector<Bytes> corpus;
  for (const std::string& name : names) {
    const std::string text = lazyboe::fuzz::read_text(name);
    corpus.emplace_back(text.begin(), text.end());
  }
  return corpus;
}

// Tokens that parsers treat specially: numbers at the edges of ranges, JSON and CSV syntax.
const std::vector<std::string>& tokens() {
  static const std::vector<std::string> t = {
      "0",     "-1",   "1e308",   "-1e308",     "1e-320",
      "nan",   "inf",  "0x10",    "4294967297", "18446744073709551616",
      "9.3e9", "\"",   "\\u0000", "\xff",       ",",
      "\n",    "{",    "}",       "[",          "]",
      ":",     "null", "true",    "\"\"",       "<",
      ">",     "/>",   "=\"",     "HDF",        "\x89HDF\r\n\x1a\n"};
  return t;
}

void mutate(Bytes& b, const std::vector<Bytes>& corpus, std::mt19937_64& rng) {
  auto pick = [&](size_t n) { return n == 0 ? size_t{0} : static_cast<size_t>(rng() % n); };
  const int steps = 1 + static_cast<int>(rng() % 4);
  for (int s = 0; s < steps; ++s) {
    switch (rng() % 6) {
      case 0:  // flip a bit
        if (!b.empty()) b[pick(b.size())] ^= static_cast<uint8_t>(1u << (rng() % 8));
        break;
      case 1:  // set a byte
        if (!b.empty()) b[pick(b.size())] = static_cast<uint8_t>(rng());
        break;
      case 2: {  // insert a token
        const std::string& t = tokens()[pick(tokens().size())];
        b.insert(b.begin() + pick(b.size() + 1), t.begin(), t.end());
        break;
      }
      case 3: {  // cut a range
        if (b.empty()) break;
        const size_t at = pick(b.size()), n = 1 + pick(std::min<size_t>(b.size() - at, 64));
        b.erase(b.begin() + at, b.begin() + at + n);
        break;
      }
      case 4: {  // duplicate a range
        if (b.empty()) break;
        const size_t at = pick(b.size()), n = 1 + pick(std::min<size_t>(b.size() - at, 64));
        const Bytes copy(b.begin() + at, b.begin() + at + n);
        b.insert(b.begin() + pick(b.size() + 1), copy.begin(), copy.end());
        break;
      }
      default: {  // splice: the head of this input, the tail of another
        const Bytes& other = corpus[pick(corpus.size())];
        const size_t head = pick(b.size() + 1), tail = pick(other.size() + 1);
        b.resize(head);
        b.insert(b.end(), other.begin() + tail, other.end());
      }
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s CORPUS_DIR [SECONDS [SEED [REPLAY_DIR...]]]\n", argv[0]);
    return 2;
  }
  size_t replayed = 0;
  for (int k = 4; k < argc; ++k) {
    std::vector<std::string> names;
    for (const Bytes& input : read_corpus(argv[k], names)) {
      LLVMFuzzerTestOneInput(input.data(), input.size());
      ++replayed;
    }
  }
  const double seconds = argc > 2 ? std::atof(argv[2]) : 2.0;
  const uint64_t seed = argc > 3 ? std::strtoull(argv[3], nullptr, 10) : 1;
  std::vector<std::string> names;
  const std::vector<Bytes> corpus = read_corpus(argv[1], names);
  if (corpus.empty()) {
    std::fprintf(stderr, "%s: no corpus files in %s\n", argv[0], argv[1]);
    return 1;
  }
  for (size_t k = 0; k < corpus.size(); ++k) {
    const Bytes& input = corpus[k];
    LLVMFuzzerTestOneInput(input.data(), input.size());
  }
  std::mt19937_64 rng(seed);
  const auto start = std::chrono::steady_clock::now();
  const auto deadline = start + std::chrono::duration<double>(seconds);
  long mutations = 0;
  while (std::chrono::steady_clock::now() < deadline) {
    Bytes input = corpus[rng() % corpus.size()];
    mutate(input, corpus, rng);
    LLVMFuzzerTestOneInput(input.data(), input.size());
    ++mutations;
  }
  std::printf(
      "%zu corpus files, %zu past findings and %ld seeded mutations (seed %llu) ran without a "
      "finding\n",
      corpus.size(), replayed, mutations, static_cast<unsigned long long>(seed));
  return 0;
}
