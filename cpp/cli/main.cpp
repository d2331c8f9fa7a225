#include <fcntl.h>

#include <iostream>

#include "cli/cli.h"

int main(int argc, char** argv) {
  // A closed standard stream (a job scheduler, `<&-`) would hand fd 0-2 to
  // the next file opened, and output meant for a terminal would land in it.
  for (int fd = 0; fd <= 2; ++fd)
    if (::fcntl(fd, F_GETFD) == -1) ::open("/dev/null", fd == 0 ? O_RDONLY : O_WRONLY);
  return penumbra::run_cli(argc, argv, std::cout, std::cerr);
}
