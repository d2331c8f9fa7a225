// Temporary files that say who made them, so that what a killed process left
// behind (kill -9, power loss) can be told from what a live one is writing,
// also when several machines share a folder.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>

namespace penumbra {

// The whole file, as bytes; empty when it is missing or unreadable (for
// logs and stamps, whose absence the caller handles as "nothing there").
std::string read_file(const std::string& path);

// Why `path` cannot be read as an input file ("" when it is a regular file,
// after symbolic links): "no such file", "is a folder", "is a FIFO ...",
// "is a character device ..." (/dev/zero would be read forever), or the
// system's reason (a symbolic-link loop). Callers put it into their one line.
std::string input_file_problem(const std::string& path);

// This machine's host name, reduced to [A-Za-z0-9-] ("host" if none).
const std::string& host_tag();

// A hidden name in the folder of `path` for writing it: ".STEM.penumbra-tmp.HOST.PID.N.EXT"
// (the extension kept, since OpenImageIO picks the format from it). N counts
// within the process, so two threads never share a name.
std::string temporary_name(const std::string& path);

// The marker of work folders: ".penumbra-work.RENDERER.HOST.PID.XXXXXX".
std::string work_folder_pattern(const std::string& renderer);

// Removes, directly inside `folder`, temporary files and work folders made by
// processes of this host that no longer run. Returns how many entries went.
std::size_t remove_stale_temporaries(const std::string& folder);

// A new file written with checked write(2)s. A full disk or a quota often
// shows only at close or fsync, so finish() checks both; until it returns,
// the content may be incomplete. The first failure is kept in error() and
// thrown (std::runtime_error) by write, seek and finish alike, also when a
// caller (OpenEXR's destructors) swallowed an earlier throw.
class CheckedFile {
 public:
  explicit CheckedFile(const std::string& path);  // created exclusively; throws if it cannot be
  ~CheckedFile();
  CheckedFile(const CheckedFile&) = delete;
  CheckedFile& operator=(const CheckedFile&) = delete;
  void write(const void* data, std::size_t bytes);
  void seek(std::uint64_t position);
  std::uint64_t tell() const { return position_; }
  void finish();  // fsync and close
  const std::string& error() const { return error_; }

 private:
  [[noreturn]] void fail(const std::string& what);
  int fd_ = -1;
  std::uint64_t position_ = 0;
  std::string error_;
};

// Writes `path` whole or not at all: `fill` writes the content into a
// temporary_name(path), which is renamed over `path` only when every write,
// the fsync and the close succeeded; otherwise it is removed and the reason
// thrown as std::runtime_error. The one way Penumbra writes its outputs.
void write_atomically(const std::string& path, const std::function<void(CheckedFile&)>& fill);

inline constexpr const char* kFolderLockName = ".penumbra-lock";

// An exclusive flock(2) on FOLDER/.penumbra-lock, held while the object
// lives (and released by the kernel when the process dies, kill -9
// included). The file says who holds it: "pid N on HOST".
class FolderLock {
 public:
  // Throws FolderLocked when another process holds the lock, and
  // std::runtime_error when the lock file cannot be made.
  explicit FolderLock(const std::string& folder);
  ~FolderLock();
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  int fd_ = -1;
};
struct FolderLocked : std::runtime_error {
  using std::runtime_error::runtime_error;  // what(): the holder, as its lock file says
};

}  // namespace penumbra
