#include "util/files.h"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
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

}  // namespace penumbra
