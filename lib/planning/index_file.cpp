#include "lazyboe/planning/index_file.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "lazyboe/bundle/bundle_file.h"
#include "lazyboe/common/error.h"
#include "lazyboe/common/hash.h"

namespace lazyboe {

IndexFileBytes read_index_file(const std::string& path, bool memory_map, size_t min_bytes) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) fail(path, std::string("cannot open: ") + std::strerror(errno));
  const auto refuse = [&](const std::string& why) {
    ::close(fd);
    fail(path, why);
  };
  struct stat st {};
  if (::fstat(fd, &st) != 0) refuse(std::string("cannot stat: ") + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) refuse("not a regular file");
  if (st.st_size < static_cast<off_t>(min_bytes)) refuse("truncated or malformed");
  IndexFileBytes f;
  f.size = static_cast<size_t>(st.st_size);
  if (memory_map) {
    void* map = ::mmap(nullptr, f.size, PROT_READ, MAP_SHARED, fd, 0);
    if (map == MAP_FAILED) refuse(std::string("cannot memory-map: ") + std::strerror(errno));
    f.storage = std::shared_ptr<const void>(map, FileUnmap{f.size});
    f.data = static_cast<const char*>(map);
  } else {
    auto bytes = std::make_shared<std::string>(f.size, '\0');
    for (size_t done = 0; done < f.size;) {
      const ssize_t n = ::pread(fd, bytes->data() + done, f.size - done, static_cast<off_t>(done));
      if (n <= 0 && !(n < 0 && errno == EINTR))
        refuse(n < 0 ? std::string("cannot read: ") + std::strerror(errno) : "truncated");
      if (n > 0) done += static_cast<size_t>(n);
    }
    f.data = bytes->data();
    f.storage = std::move(bytes);
  }
  ::close(fd);  // a mapping stays valid
  return f;
}

std::string bundle_states_fingerprint(const BundleView& bundle) {
  if (!bundle.states_checksum().empty()) return bundle.states_checksum();
  const size_t bytes = bundle.size() * static_cast<size_t>(bundle.dof()) * sizeof(double);
  std::string out;
  for (const double* rows :
       {bundle.size() ? bundle.q0(0) : nullptr, bundle.size() ? bundle.qf(0) : nullptr}) {
    Fnv1a64 hash;
    hash.update(rows, rows ? bytes : 0);
    out += (out.empty() ? "" : " ") + std::string(kChecksumPrefix) + hash.hex();
  }
  return out;
}

}  // namespace lazyboe
