// This process's use of the machine so far, for the timing commands
// (`penumbra bench`, `penumbra pyramid`).
#pragma once

namespace penumbra {

// The largest resident set so far, MiB.
double peak_rss_mib();

// The resident set now (MiB, /proc/self/statm); 0 where it cannot be read.
double current_rss_mib();

// User and system CPU seconds so far of this process (all its threads).
double cpu_seconds();

// The same, and of the children it waited for (an external renderer's
// processes).
double cpu_seconds_with_children();

}  // namespace penumbra
