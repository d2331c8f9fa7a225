#include "util/resource_usage.h"

#include <sys/resource.h>
#include <unistd.h>

#include <fstream>

namespace penumbra {

namespace {

double cpu_seconds_of(int who) {
  rusage usage{};
  getrusage(who, &usage);
  const auto seconds = [](const timeval& t) { return double(t.tv_sec) + 1e-6 * double(t.tv_usec); };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

}  // namespace

double peak_rss_mib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_maxrss) / 1024.0;  // Linux reports KiB
}

double current_rss_mib() {
  std::ifstream statm("/proc/self/statm");
  double pages_total = 0.0, pages_resident = 0.0;
  if (!(statm >> pages_total >> pages_resident)) return 0.0;
  return pages_resident * double(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

double cpu_seconds() {
  return cpu_seconds_of(RUSAGE_SELF);
}

double cpu_seconds_with_children() {
  return cpu_seconds_of(RUSAGE_SELF) + cpu_seconds_of(RUSAGE_CHILDREN);
}

}  // namespace penumbra
