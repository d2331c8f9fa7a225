#include "study/figures.h"

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string_view>

#include <fmt/format.h>

#include "renderers/renderers.h"
#include "util/data_files.h"
#include "util/process.h"

namespace penumbra {
namespace fs = std::filesystem;

namespace {

std::string python_executable(const std::string& preferred) {
  if (!preferred.empty()) return preferred;
  if (const char* env = std::getenv("PENUMBRA_PYTHON")) return env;
  // Debian's interpreter, where python3-matplotlib lives, even when a
  // different python3 comes first in PATH.
  if (find_executable("/usr/bin/python3")) return "/usr/bin/python3";
  return "python3";
}

}  // namespace

namespace {

// Lines of the script's log that begin with this are progress
// (harness/penumbra_plot.py progress()); the rest is kept for errors.
constexpr std::string_view kProgress = "progress: ";

// Forwards the progress lines appended to the log since the last call.
class ProgressTail {
 public:
  ProgressTail(std::string path, ProgressLog log) : path_(std::move(path)), log_(std::move(log)) {}
  // Every quarter second at most: the caller polls every 25 ms.
  void poll(bool force = false) {
    if (!log_) return;
    const auto now = std::chrono::steady_clock::now();
    if (!force && now - last_ < std::chrono::milliseconds(250)) return;
    last_ = now;
    std::ifstream in(path_, std::ios::binary);
    if (!in || !in.seekg(static_cast<std::streamoff>(read_))) return;
    std::string line;
    while (std::getline(in, line)) {
      if (in.eof()) break;  // an unfinished line: read it whole next time
      read_ += line.size() + 1;
      if (line.rfind(kProgress, 0) == 0) log_(line.substr(kProgress.size()));
    }
  }

 private:
  std::string path_;
  ProgressLog log_;
  std::size_t read_ = 0;
  std::chrono::steady_clock::time_point last_{};
};

}  // namespace

void run_plot_script(const std::vector<std::string>& arguments, const std::string& log_path,
                     const std::string& python, double timeout_s, const ProgressLog& progress) {
  std::error_code ignored;
  fs::remove(log_path, ignored);
  const std::string name = python_executable(python);
  const auto exe = find_executable(name);
  if (!exe)
    throw RendererError(fmt::format(
        "{} not found: install python3, python3-matplotlib and python3-jinja2 (apt-get install "
        "python3-matplotlib python3-jinja2)",
        name));
  const std::string script = data_file("harness/report.py");
  if (!fs::is_regular_file(script))
    throw RendererError(fmt::format("the report script {} is missing", script));
  std::vector<std::string> argv{*exe, script};
  argv.insert(argv.end(), arguments.begin(), arguments.end());
  fs::path dir = fs::path(log_path).parent_path();
  // A coprocess, polled, so that its progress lines reach the user while
  // it runs (its stdin is unused: the script never reads it).
  Coprocess child(argv, dir.empty() ? "." : dir.string(), log_path);
  ProgressTail tail(log_path, progress);
  const std::optional<ProcessResult> end = child.wait_until(
      [&] {
        tail.poll();
        return false;
      },
      timeout_s);
  tail.poll(true);
  const ProcessResult p = end.value_or(ProcessResult{});
  if (!p.ok())
    throw RendererError(
        fmt::format("harness/report.py failed ({}); log {}:\n{}",
                    p.timed_out ? std::string("timed out") : "exit " + std::to_string(p.exit_code),
                    log_path, tail_lines(log_path, 12)));
}

std::string draw_report(const std::string& folder, bool self_contained, const std::string& python,
                        double timeout_s, const ProgressLog& progress) {
  const fs::path out(folder);
  std::vector<std::string> arguments{"report", fs::absolute(out).string()};
  if (self_contained) arguments.push_back("--self-contained");
  run_plot_script(arguments, (out / "report.log").string(), python, timeout_s, progress);
  return (out / "report.html").string();
}

}  // namespace penumbra
