// Atomic file output (temp file + fsync + rename); see atomic_file.hpp.
#include "tools/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>
#include <system_error>

namespace turbid::tools {
namespace fs = std::filesystem;

namespace {

std::string errno_text(int err) { return std::error_code(err, std::generic_category()).message(); }

[[noreturn]] void fail(const std::string& what, const fs::path& p, int err) {
  throw std::runtime_error(what + " '" + p.string() + "': " + errno_text(err));
}

void fsync_path(const fs::path& p) {
  const int fd = ::open(p.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) fail("cannot open for fsync", p, errno);
  if (::fsync(fd) != 0) {
    const int err = errno;
    ::close(fd);
    fail("fsync failed for", p, err);
  }
  ::close(fd);
}

fs::path directory_of(const fs::path& target) {
  const fs::path parent = target.parent_path();
  return parent.empty() ? fs::path(".") : parent;
}

}  // namespace

fs::path temp_path_for(const fs::path& target) {
  fs::path tmp = target;
  tmp += ".tmp-" + std::to_string(::getpid());
  return tmp;
}

void sync_directory(const fs::path& dir) {
  // Some file systems refuse fsync on a directory; the rename itself is still atomic there.
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  (void)::fsync(fd);
  ::close(fd);
}

void commit_temp_file(const fs::path& temp, const fs::path& target) {
  try {
    fsync_path(temp);
    std::error_code ec;
    fs::rename(temp, target, ec);
    if (ec)
      throw std::runtime_error("cannot rename '" + temp.string() + "' to '" + target.string() +
                               "': " + ec.message());
  } catch (...) {
    std::error_code ignore;
    fs::remove(temp, ignore);
    throw;
  }
  sync_directory(directory_of(target));
}

void write_file_atomic(const fs::path& target, std::span<const std::byte> bytes) {
  const fs::path temp = temp_path_for(target);
  const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) fail("cannot create", temp, errno);
  const std::byte* p = bytes.data();
  std::size_t left = bytes.size();
  while (left > 0) {
    const ssize_t w = ::write(fd, p, left);
    if (w < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      ::close(fd);
      ::unlink(temp.c_str());
      fail("cannot write", temp, err);
    }
    p += w;
    left -= std::size_t(w);
  }
  int err = ::fsync(fd) == 0 ? 0 : errno;
  if (::close(fd) != 0 && err == 0) err = errno;
  if (err != 0) {
    ::unlink(temp.c_str());
    fail("cannot flush", temp, err);
  }
  std::error_code ec;
  fs::rename(temp, target, ec);
  if (ec) {
    fs::remove(temp, ec);
    throw std::runtime_error("cannot rename '" + temp.string() + "' to '" + target.string() +
                             "': " + ec.message());
  }
  sync_directory(directory_of(target));
}

void write_text_atomic(const fs::path& target, std::string_view text) {
  write_file_atomic(target, std::as_bytes(std::span<const char>(text.data(), text.size())));
}

}  // namespace turbid::tools
