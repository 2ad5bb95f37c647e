// The CPUs this process may run on: its affinity mask (what taskset or a Slurm allocation
// leave it), not the machine's count. Every "0: use the cores" default
// (the planner's swarm runs, the diagnosis' candidates) takes it, so a process confined to one
// CPU does not start a thread per core of the machine.
#pragma once

#include <vector>

namespace twin {

/// The CPUs of this process's affinity mask, in increasing order; where the mask cannot be
/// read, 0 .. (online CPUs - 1).
std::vector<int> UsableCpuList();

/// UsableCpuList().size(), at least 1.
int UsableCpuCount();

}  // namespace twin
