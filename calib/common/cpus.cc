#include "calib/common/cpus.h"

#include <sched.h>
#include <unistd.h>

#include <algorithm>

namespace twin {

std::vector<int> UsableCpuList() {
  std::vector<int> cpus;
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) == 0) {
    for (int c = 0; c < CPU_SETSIZE; ++c) {
      if (CPU_ISSET(c, &set)) cpus.push_back(c);
    }
  }
  if (cpus.empty()) {
    const long online = std::clamp(sysconf(_SC_NPROCESSORS_ONLN), 1L, 4096L);
    for (long c = 0; c < online; ++c) cpus.push_back(static_cast<int>(c));
  }
  return cpus;
}

int UsableCpuCount() { return std::max(1, static_cast<int>(UsableCpuList().size())); }

}  // namespace twin
