// A per-link table of what a session derives from its bundle for one link (EndPoseIndex,
// EdgeLinkMotion), each made at its first use and kept. Thread-safe; a table once made stays
// (and its reference valid) as long as this.
#pragma once

#include <map>
#include <memory>
#include <mutex>

#include "lazyboe/bundle/bundle_view.h"
#include "lazyboe/robot/robot_model.h"

namespace lazyboe {

// T is made as T(bundle, robot, link).
template <typename T>
class PerLink {
 public:
  PerLink(const BundleView& bundle, const RobotModel& robot) : bundle_(bundle), robot_(robot) {}
  PerLink(const PerLink&) = delete;
  PerLink& operator=(const PerLink&) = delete;

  const T& of(int link) const {
    std::lock_guard<std::mutex> lock(mutex_);
    std::unique_ptr<T>& made = made_[link];
    if (!made) made = std::make_unique<T>(bundle_, robot_, link);
    return *made;
  }

 private:
  const BundleView& bundle_;
  const RobotModel& robot_;
  mutable std::mutex mutex_;
  mutable std::map<int, std::unique_ptr<T>> made_;
};

}  // namespace lazyboe
