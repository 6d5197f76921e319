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

namespace {
uint32_t rotl(uint32_t x, int k) { return (x << k) | (x >> (32 - k)); }
}  // namespace

uint32_t lookup3(const void* data, size_t size, uint32_t initval) {
  const auto* k = static_cast<const unsigned char*>(data);
  uint32_t a, b, c;
  a = b = c = 0xdeadbeefu + static_cast<uint32_t>(size) + initval;
  auto word = [&](size_t i) {
    return uint32_t{k[i]} | uint32_t{k[i + 1]} << 8 | uint32_t{k[i + 2]} << 16 |
           uint32_t{k[i + 3]} << 24;
  };
  while (size > 12) {
    a += word(0);
    b += word(4);
    c += word(8);
    a -= c, a ^= rotl(c, 4), c += b;  // mix
    b -= a, b ^= rotl(a, 6), a += c;
    c -= b, c ^= rotl(b, 8), b += a;
    a -= c, a ^= rotl(c, 16), c += b;
    b -= a, b ^= rotl(a, 19), a += c;
    c -= b, c ^= rotl(b, 4), b += a;
    size -= 12;
    k += 12;
  }
  if (size == 0) return c;
  uint32_t tail[3] = {0, 0, 0};  // the last 1..12 bytes, little-endian, zero-padded
  for (size_t i = 0; i < size; ++i) tail[i / 4] |= uint32_t{k[i]} << (8 * (i % 4));
  a += tail[0];
  b += tail[1];
  c += tail[2];
  c ^= b, c -= rotl(b, 14);  // final
  a ^= c, a -= rotl(c, 11);
  b ^= a, b -= rotl(a, 25);
  c ^= b, c -= rotl(b, 16);
  a ^= c, a -= rotl(c, 4);
  b ^= a, b -= rotl(a, 14);
  c ^= b, c -= rotl(b, 24);
  return c;
}

}  // namespace lazyboe
