// The commands that run one part of harness/report.py over a finished study
// folder (figure, table): the script does the work from report.json alone;
// the command forwards its options and passes its output and exit status on.
#pragma once

#include <string>
#include <vector>

#include "cli/command.h"

namespace penumbra {

// Runs `report.py ARGUMENTS`; its output lines (progress left out) go to
// c.out when it succeeds, to c.err when not. Exit 2 (bad input) stays 2;
// any other failure is 1.
int run_plot_command(const std::vector<std::string>& arguments, const CommandContext& c);

// "--name value" for each option given (value not empty).
void forward_option(std::vector<std::string>& arguments, const std::string& name,
                    const std::string& value);

}  // namespace penumbra
