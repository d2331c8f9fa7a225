#include "study/figures.h"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string_view>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "image/image_io.h"
#include "renderers/renderers.h"
#include "study/provenance.h"
#include "util/data_files.h"
#include "util/files.h"
#include "util/hash.h"
#include "util/process.h"
#include "util/version.h"

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

ProcessResult run_plot_process(const std::vector<std::string>& arguments,
                               const std::string& log_path, const std::string& python,
                               double timeout_s, const ProgressLog& progress,
                               const std::string& working_dir) {
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
  fs::path dir = working_dir.empty() ? fs::path(log_path).parent_path() : fs::path(working_dir);
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
  return end.value_or(ProcessResult{});
}

void run_plot_script(const std::vector<std::string>& arguments, const std::string& log_path,
                     const std::string& python, double timeout_s, const ProgressLog& progress) {
  const ProcessResult p = run_plot_process(arguments, log_path, python, timeout_s, progress);
  // Stopped by Ctrl-C or SIGTERM: an interruption, not a failure of the script.
  if (p.cancelled) throw RenderCancelled("the figures were not drawn (interrupted)");
  if (!p.ok())
    throw RendererError(
        fmt::format("harness/report.py failed ({}); log {}:\n{}",
                    p.timed_out ? std::string("timed out") : "exit " + std::to_string(p.exit_code),
                    log_path, tail_lines(log_path, 12)));
}

bool is_progress_line(std::string_view line) {
  return line.rfind(kProgress, 0) == 0;
}

namespace {

constexpr const char* kStampName = "figures/.inputs";

// Everything the figures are drawn from: report.json names every render by
// its content key (so the same text means the same images), the harness's
// scripts and templates, the interpreter and the HTML mode.
std::string figure_inputs_digest(const fs::path& out, bool self_contained,
                                 const std::string& python) {
  std::uint64_t h = fnv1a(without_run_keys(read_file((out / "report.json").string())));
  h = fnv1a(read_file((out / "lowpoly.csv").string()), h);
  // The report's "What is achievable" section (study/fit.h), when fitted.
  if (fs::is_regular_file(out / "fit" / "fit.json"))
    h = fnv1a(without_run_keys(read_file((out / "fit" / "fit.json").string())), h);
  // The scripts, the page's templates and style sheet, and the column
  // table; not __pycache__, which Python rewrites as it pleases.
  const fs::path harness = fs::path(data_file("harness/report.py")).parent_path();
  std::vector<fs::path> sources;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(harness, ec);
       !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    if (it->is_directory() && it->path().filename() == "__pycache__") {
      it.disable_recursion_pending();
      continue;
    }
    const std::string ext = it->path().extension().string();
    if (ext == ".py" || ext == ".j2" || ext == ".css" || ext == ".json")
      sources.push_back(it->path());
  }
  std::sort(sources.begin(), sources.end());
  for (const fs::path& s : sources)
    h = fnv1a(fs::relative(s, harness).string() + "\n" + read_file(s.string()), h);
  h = fnv1a(python_executable(python) + (self_contained ? "\nself-contained" : "\nlinked") + "\n" +
                kPenumbraVersion,
            h);
  return fmt::format("{:016x}", h);
}

// The stamp holds the digest, then the files the script wrote; all must
// still be there for the last drawing to count.
bool drawing_is_current(const fs::path& out, const std::string& digest) {
  std::ifstream in(out / kStampName);
  std::string line;
  if (!std::getline(in, line) || line != digest) return false;
  std::size_t files = 0;
  while (std::getline(in, line)) {
    if (!fs::is_regular_file(line)) return false;
    ++files;
  }
  return files > 0;
}

void write_stamp(const fs::path& out, const std::string& digest, const std::string& log_path) {
  std::string text = digest + "\n";
  std::ifstream log(log_path);
  // The script prints the paths it wrote, one per line, after its progress.
  for (std::string line; std::getline(log, line);)
    if (line.rfind(kProgress, 0) != 0 && fs::path(line).is_absolute() && fs::is_regular_file(line))
      text += line + "\n";
  try {
    write_text_file((out / kStampName).string(), text);
  } catch (const OutputError&) {  // without a stamp, the next run draws again
  }
}

// What the script's atomic writes (harness/penumbra_plot.py, replacing())
// leave when it is killed: hidden temporaries beside the figures.
void remove_script_temporaries(const fs::path& out) {
  std::error_code ec;
  std::vector<fs::path> found;
  for (auto it = fs::recursive_directory_iterator(out, ec);
       !ec && it != fs::recursive_directory_iterator(); it.increment(ec))
    if (it->path().filename().string().rfind(".penumbra-draw-", 0) == 0)
      found.push_back(it->path());
  for (const fs::path& f : found) fs::remove(f, ec);
}

}  // namespace

std::string draw_report(const std::string& folder, bool self_contained, const std::string& python,
                        double timeout_s, const ProgressLog& progress, bool reuse_unchanged) {
  const fs::path out(folder);
  const std::string html = (out / "report.html").string();
  const std::string digest = figure_inputs_digest(out, self_contained, python);
  if (reuse_unchanged && drawing_is_current(out, digest)) {
    if (progress)
      progress(
          "report.json, lowpoly.csv and the scripts are unchanged: kept the figures and "
          "report.html of the last run (`penumbra report` redraws them)");
    return html;
  }
  std::error_code ignored;
  fs::remove(out / kStampName, ignored);  // a drawing killed halfway is not current
  std::vector<std::string> arguments{"report", fs::absolute(out).string()};
  if (self_contained) arguments.push_back("--self-contained");
  const std::string log_path = (out / "report.log").string();
  try {
    run_plot_script(arguments, log_path, python, timeout_s, progress);
  } catch (...) {
    remove_script_temporaries(out);
    throw;
  }
  write_stamp(out, digest, log_path);
  return html;
}

}  // namespace penumbra
