#include "util/files.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>

#include <fmt/format.h>

namespace penumbra {
namespace fs = std::filesystem;

std::string input_file_problem(const std::string& path) {
  if (path.empty()) return "expected a file name, got \"\"";
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (ec && status.type() != fs::file_type::not_found) return "cannot be opened: " + ec.message();
  switch (status.type()) {
    case fs::file_type::regular:
      return "";
    case fs::file_type::not_found:
      return "no such file";
    case fs::file_type::directory:
      return "is a folder, not a file";
    case fs::file_type::fifo:
      return "is a FIFO (named pipe), not a regular file";
    case fs::file_type::character:
      return "is a character device, not a regular file";
    case fs::file_type::block:
      return "is a block device, not a regular file";
    case fs::file_type::socket:
      return "is a socket, not a regular file";
    default:
      return "is not a regular file";
  }
}

const std::string& host_tag() {
  static const std::string tag = [] {
    char name[256] = {};
    std::string out;
    if (::gethostname(name, sizeof(name) - 1) == 0)
      for (const char* c = name; *c; ++c)
        if ((*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') || (*c >= '0' && *c <= '9') ||
            *c == '-')
          out += *c;
    return out.empty() ? std::string("host") : out;
  }();
  return tag;
}

std::string temporary_name(const std::string& path) {
  static std::atomic<unsigned long> counter{0};
  const fs::path p(path);
  return (p.parent_path() / fmt::format(".{}.penumbra-tmp.{}.{}.{}{}", p.stem().string(),
                                        host_tag(), ::getpid(), counter++, p.extension().string()))
      .string();
}

std::string work_folder_pattern(const std::string& renderer) {
  return fmt::format(".penumbra-work.{}.{}.{}.XXXXXX", renderer, host_tag(), ::getpid());
}

std::size_t remove_stale_temporaries(const std::string& folder) {
  static const std::regex temporary(R"(^\..*\.penumbra-tmp\.([A-Za-z0-9-]+)\.([0-9]+)\.[0-9]+.*$)");
  static const std::regex work(R"(^\.penumbra-work\.[a-z]+\.([A-Za-z0-9-]+)\.([0-9]+)\.[^.]+$)");
  std::size_t removed = 0;
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    std::smatch m;
    if (!std::regex_match(name, m, temporary) && !std::regex_match(name, m, work)) continue;
    if (m[1].str() != host_tag()) continue;  // another machine's: it may be alive
    const long pid = std::stol(m[2].str());
    if (pid <= 0 || pid == ::getpid()) continue;
    if (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;  // still running
    std::error_code ignored;
    if (fs::remove_all(it->path(), ignored) > 0) ++removed;
  }
  return removed;
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

CheckedFile::CheckedFile(const std::string& path) {
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd_ < 0) fail("cannot create it");
}

CheckedFile::~CheckedFile() {
  if (fd_ >= 0) ::close(fd_);
}

void CheckedFile::fail(const std::string& what) {
  if (error_.empty()) error_ = fmt::format("{}: {}", what, std::strerror(errno));
  throw std::runtime_error(error_);
}

void CheckedFile::write(const void* data, std::size_t bytes) {
  if (!error_.empty()) throw std::runtime_error(error_);
  const char* p = static_cast<const char*>(data);
  while (bytes > 0) {
    const ssize_t n = ::write(fd_, p, bytes);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      if (n == 0) errno = ENOSPC;
      fail("write failed");
    }
    p += n;
    bytes -= std::size_t(n);
    position_ += std::uint64_t(n);
  }
}

void CheckedFile::seek(std::uint64_t position) {
  if (!error_.empty()) throw std::runtime_error(error_);
  if (::lseek(fd_, off_t(position), SEEK_SET) < 0) fail("seek failed");
  position_ = position;
}

void CheckedFile::finish() {
  if (!error_.empty()) throw std::runtime_error(error_);
  if (::fsync(fd_) != 0) fail("fsync failed");
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0) fail("close failed");
}

void write_atomically(const std::string& path, const std::function<void(CheckedFile&)>& fill) {
  const std::string temporary = temporary_name(path);
  std::error_code ec;
  try {
    CheckedFile file(temporary);
    fill(file);
    file.finish();
  } catch (...) {
    fs::remove(temporary, ec);
    throw;
  }
  fs::rename(temporary, path, ec);
  if (ec) {
    const std::string why = ec.message();
    fs::remove(temporary, ec);
    throw std::runtime_error("cannot move the finished file into place: " + why);
  }
}

FolderLock::FolderLock(const std::string& folder) {
  const std::string path = (fs::path(folder) / kFolderLockName).string();
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0)
    throw std::runtime_error(fmt::format("{}: cannot create: {}", path, std::strerror(errno)));
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    ::close(fd_);
    fd_ = -1;
    if (error != EWOULDBLOCK)
      throw std::runtime_error(fmt::format("{}: cannot lock: {}", path, std::strerror(error)));
    std::string holder = read_file(path);
    while (!holder.empty() && (holder.back() == '\n' || holder.back() == ' ')) holder.pop_back();
    throw FolderLocked(holder.empty() ? std::string("a process that has not said which") : holder);
  }
  // Only the holder writes the file, so a reader sees the current holder
  // (or, for a moment, nothing).
  const std::string text = fmt::format("pid {} on {}\n", ::getpid(), host_tag());
  if (::ftruncate(fd_, 0) != 0 || ::pwrite(fd_, text.data(), text.size(), 0) < 0) {
    // who holds it is a courtesy; the lock itself holds
  }
}

FolderLock::~FolderLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the lock
}

}  // namespace penumbra
