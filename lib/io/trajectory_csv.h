// Reading a joint trajectory CSV in the format lazyboe-query writes (write_trajectory_csv):
// header `t,q1..qn,dq1..dqn`, then any further columns (ddq, commands, ...), which are read
// and checked as numbers like the rest but not returned.
#pragma once

#include <string>
#include <vector>

#include "lazyboe/sim/trajectory_check.h"

namespace lazyboe {

struct TrajectoryCsv {
  std::string path;
  int dof = 0;
  std::vector<double> t, q, dq;  // q and dq row-major, samples x dof
  std::vector<int> line;         // source line of each sample, for messages
  TrajectoryView view() const {
    return TrajectoryView{static_cast<int>(t.size()), dof, t.data(), q.data(), dq.data()};
  }
};

// Throws Error("<path>:<line>: ...") for a header that does not start with t,q1..qn,dq1..dqn,
// a row of the wrong width or a value that is not a finite number (read_numeric_csv's checks);
// Error("<path>: ...") for a missing or empty file or one without samples.
TrajectoryCsv read_trajectory_csv(const std::string& path, int dof);

}  // namespace lazyboe
