#include "study/figures.h"

#include <cstdlib>
#include <filesystem>

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

void run_plot_script(const std::vector<std::string>& arguments, const std::string& log_path,
                     const std::string& python, double timeout_s) {
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
  const ProcessResult p = run_process(argv, dir.empty() ? "." : dir.string(), log_path, timeout_s);
  if (!p.ok())
    throw RendererError(
        fmt::format("harness/report.py failed ({}); log {}:\n{}",
                    p.timed_out ? std::string("timed out") : "exit " + std::to_string(p.exit_code),
                    log_path, tail_lines(log_path, 12)));
}

std::string draw_report(const std::string& folder, const std::string& python, double timeout_s) {
  const fs::path out(folder);
  run_plot_script({"report", fs::absolute(out).string()}, (out / "report.log").string(), python,
                  timeout_s);
  return (out / "report.html").string();
}

}  // namespace penumbra
