#include "hof/core/file_write.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

namespace hof {
namespace {

std::unexpected<Error> io_error(const std::filesystem::path& path, const std::string& what, int error_number) {
  return make_error(ErrorCode::kIo, what + ": " + std::strerror(error_number), path.string());
}

}  // namespace

Expected<void> write_file_atomically(const std::filesystem::path& path, std::string_view content) {
  // Same folder as the target, so the rename never crosses file systems; the PID keeps two
  // processes saving the same file from sharing a temporary.
  const std::filesystem::path temporary = path.string() + ".tmp-" + std::to_string(::getpid());
  mode_t mode = 0644;
  if (struct stat existing{}; ::stat(path.c_str(), &existing) == 0) {
    if (S_ISDIR(existing.st_mode)) return make_error(ErrorCode::kIo, "is a folder, not a file", path.string());
    mode = existing.st_mode & 07777U;
  }
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, mode);
  if (fd < 0) return io_error(path, "cannot write", errno);
  const auto abandon = [&](const std::string& what, int error_number) {
    ::close(fd);
    ::unlink(temporary.c_str());
    return io_error(path, what, error_number);
  };
  std::size_t done = 0;
  while (done < content.size()) {
    const ssize_t n = ::write(fd, content.data() + done, content.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      return abandon("cannot write", errno);
    }
    done += static_cast<std::size_t>(n);
  }
  // Flushed before the rename: after a power cut the name never points at missing bytes.
  if (::fsync(fd) != 0) return abandon("cannot flush to the disk", errno);
  if (::close(fd) != 0) {
    const int e = errno;
    ::unlink(temporary.c_str());
    return io_error(path, "cannot write", e);
  }
  if (::rename(temporary.c_str(), path.c_str()) != 0) {
    const int e = errno;
    ::unlink(temporary.c_str());
    return io_error(path, "cannot replace the file", e);
  }
  // The rename itself is durable once the folder is flushed (best effort: some file systems
  // refuse to open a folder for that, and the file is complete either way).
  const std::filesystem::path folder = path.has_parent_path() ? path.parent_path() : std::filesystem::path(".");
  if (const int dir = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC); dir >= 0) {
    ::fsync(dir);
    ::close(dir);
  }
  return {};
}

}  // namespace hof
