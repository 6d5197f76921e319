#include "lazyboe/common/hash.h"

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "lazyboe/common/error.h"

namespace lazyboe {
namespace {

std::string read_whole_file(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) fail(path, "cannot read: " + std::string(std::strerror(errno)));
  std::string bytes;
  char buf[1 << 16];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) bytes.append(buf, n);
  const bool bad = std::ferror(f);
  const int err = errno;
  std::fclose(f);
  if (bad) fail(path, "cannot read: " + std::string(std::strerror(err)));
  return bytes;
}

}  // namespace

void Fnv1a64::update(const void* data, size_t size) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < size; ++i) {
    h_ ^= p[i];
    h_ *= 0x100000001b3ull;
  }
}

std::string Fnv1a64::hex() const { return to_hex64(h_); }

std::string to_hex64(uint64_t value) {
  static const char digits[] = "0123456789abcdef";
  std::string s(16, '0');
  for (int i = 15; i >= 0; --i, value >>= 4) s[i] = digits[value & 0xf];
  return s;
}

std::string fnv1a64_hex(const std::string& bytes) {
  Fnv1a64 h;
  h.update(bytes);
  return h.hex();
}

std::string hash_files(const std::vector<std::string>& paths) {
  Fnv1a64 h;
  for (const std::string& path : paths) {
    const std::string bytes = read_whole_file(path);
    uint64_t n = bytes.size();
    unsigned char len[8];
    for (int i = 0; i < 8; ++i, n >>= 8) len[i] = static_cast<unsigned char>(n & 0xff);
    h.update(len, sizeof len);
    h.update(bytes);
  }
  return h.hex();
}

}  // namespace lazyboe
