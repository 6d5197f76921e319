// What the process itself uses, for the tools' load reports.
#pragma once

namespace lazyboe {

// Resident memory of this process (VmRSS), MiB; 0 where /proc is not available.
double resident_memory_mib();

}  // namespace lazyboe
