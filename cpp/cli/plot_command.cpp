#include "cli/plot_command.h"

#include <filesystem>
#include <fstream>

#include "study/figures.h"
#include "study/study.h"
#include "util/files.h"

namespace penumbra {

int run_plot_command(const std::vector<std::string>& arguments, const CommandContext& c) {
  namespace fs = std::filesystem;
  // The script's output goes through a log in the temporary folder, removed
  // however the command ends: nothing is left beside the study.
  const std::string log =
      temporary_name((fs::temp_directory_path() / "penumbra-plot.log").string());
  struct Remove {
    std::string path;
    ~Remove() {
      std::error_code ignored;
      fs::remove(path, ignored);
    }
  } remove{log};
  // In the caller's folder: the study folder and -o are paths as typed.
  const ProcessResult p = run_plot_process(arguments, log, "", kFiguresTimeoutS, nullptr, ".");
  std::ifstream in(log);
  std::ostream& to = p.ok() ? c.out : c.err;
  for (std::string line; std::getline(in, line);)
    if (!is_progress_line(line)) to << line << "\n";
  if (p.ok()) return kExitOk;
  if (p.timed_out) c.err << "penumbra: harness/report.py timed out\n";
  return p.exit_code == kExitBadInput ? kExitBadInput : kExitFailure;
}

void forward_option(std::vector<std::string>& arguments, const std::string& name,
                    const std::string& value) {
  if (value.empty()) return;
  arguments.push_back(name);
  arguments.push_back(value);
}

}  // namespace penumbra
