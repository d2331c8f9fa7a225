// The figures and report.html, drawn by harness/report.py (matplotlib and a
// Jinja2 template) from report.json alone, so they can be redrawn without
// rendering (`penumbra report DIR`).
#pragma once

#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "util/process.h"

namespace penumbra {

// Receives the script's progress lines while it runs ("profiles and image
// grid of v003 (4/24)"), without their "progress: " prefix.
using ProgressLog = std::function<void(const std::string&)>;

// Runs harness/report.py (found beside the binary, util/data_files.h) with
// `arguments`, its output in `log_path`. Python: `python`, else
// PENUMBRA_PYTHON, else /usr/bin/python3 (Debian's, which has
// python3-matplotlib and python3-jinja2), else python3. RendererError when it
// is missing, fails or times out.
void run_plot_script(const std::vector<std::string>& arguments, const std::string& log_path,
                     const std::string& python = "", double timeout_s = 600.0,
                     const ProgressLog& progress = nullptr);
// As run_plot_script, but returns how the script ended instead of throwing
// on a failure (RendererError only when Python or the script is missing):
// for commands that pass the script's own exit status on (2: bad input).
// It runs in `working_dir`, by default the log's folder; a command given
// paths as its user typed them runs it in "." so that they resolve as typed.
ProcessResult run_plot_process(const std::vector<std::string>& arguments,
                               const std::string& log_path, const std::string& python = "",
                               double timeout_s = 600.0, const ProgressLog& progress = nullptr,
                               const std::string& working_dir = "");
// A log line the script wrote as progress ("progress: ..."), not output.
bool is_progress_line(std::string_view line);

// Draws the figures and report.html of the study folder `folder` (which holds
// report.json); returns the path of report.html, which links its images
// (relative URLs into images/ and figures/) or, self_contained, embeds them.
// With `reuse_unchanged`, a drawing from the same inputs (report.json,
// lowpoly.csv, the harness scripts and templates, the interpreter;
// stamped in figures/.inputs)
// whose files are all still there is kept rather than redrawn.
std::string draw_report(const std::string& folder, bool self_contained = false,
                        const std::string& python = "", double timeout_s = 600.0,
                        const ProgressLog& progress = nullptr, bool reuse_unchanged = false);

}  // namespace penumbra
