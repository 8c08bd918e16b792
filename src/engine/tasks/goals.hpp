// A run's extra goals (issue 24): the tasks after the primary frame task, each with
// its own rows of the extended task, reference, gains and priority level (mirrors the
// goals of clik/loop/tracking.py). The rows of goal g follow those of goal g - 1,
// after the primary task's rows 0..m0.
//
// A goal kind is a config type (bound to Python, `_engine.FrameGoal`, ...) and a run
// type, its state for one run, allocated once:
//
//   struct XRun {
//     XRun(const pinocchio::Model&, const X&);  // throws std::invalid_argument
//     int rows() const;       // m_g
//     int ref_size() const;   // d_g: doubles of reference per sample
//     // error, Jacobian rows (rows, nv) and feed-forward into the extended task at row0;
//     // data: joint Jacobians, frame placements (and the CoM Jacobian) at q
//     void write(const GoalContext&, const double* ref, const double* ff,
//                ExtendedTask& ext, int row0);
//     void norms(const ExtendedTask& ext, int row0, double& first, double& second) const;
//     // where each row of its Jacobian may not be zero: [lo[i], hi[i]) (law (10)'s sums)
//     void columns(const pinocchio::Model&, int* lo, int* hi) const;
//     // what it takes as a controller's target (tasks/targets.hpp)
//     TargetReader target() const;
//   };
//
// The run visits the goals' std::variant (GoalRun): no virtual call, nothing allocated
// per sample.
#pragma once

#include <variant>
#include <vector>

#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>

#include "tasks/extended_task.hpp"
#include "tasks/targets.hpp"
#include "types.hpp"

namespace clik {

// A frame's pose, in the world or relative to another frame (`_engine.FrameGoal`).
// rows among 0..5 = (x, y, z, rx, ry, rz); relative_to -1: the world. Reference per
// sample: p (3), then R row-major (9) (relative: the pose of the frame in relative_to's).
struct FrameGoal {
  int frame = 0;
  std::vector<int> rows;
  int relative_to = -1;
};

// Joint angles of 1-DoF joints (`_engine.PostureGoal`): q[idx_q] (continuous joints:
// the angle of (cos, sin) at idx_q, idx_q + 1), velocity columns idx_v. Reference: one
// double per joint [rad or m].
struct PostureGoal {
  std::vector<int> idx_q, idx_v;
  std::vector<bool> continuous;
};

// The centre of mass (`_engine.ComGoal`), rows among 0..2. Reference: c_d (3) [m].
struct ComGoal {
  std::vector<int> rows;
};

using GoalConfig = std::variant<FrameGoal, PostureGoal, ComGoal>;

// What the goals read at one sample.
struct GoalContext {
  const pinocchio::Model& model;
  pinocchio::Data& data;  // getFrameJacobian reads it through a non-const reference
  const Vec& q;
};

class FrameGoalRun {
 public:
  FrameGoalRun(const pinocchio::Model& model, const FrameGoal& goal);
  int rows() const { return static_cast<int>(rows_.size()); }
  int ref_size() const { return 12; }
  void write(const GoalContext& c, const double* ref, const double* ff, ExtendedTask& ext,
             int row0);
  void norms(const ExtendedTask& ext, int row0, double& first, double& second) const;
  void columns(const pinocchio::Model& model, int* lo, int* hi) const;
  TargetReader target() const;
  int frame() const { return frame_; }
  int relative_to() const { return relative_to_; }

 private:
  int frame_, relative_to_;
  std::vector<int> rows_;
  Eigen::Matrix<double, 6, Eigen::Dynamic> Ja_, Jb_;
  Eigen::Matrix<double, 6, 1> e6_;
};

class PostureGoalRun {
 public:
  PostureGoalRun(const pinocchio::Model& model, const PostureGoal& goal);
  int rows() const { return static_cast<int>(idx_q_.size()); }
  int ref_size() const { return rows(); }
  void write(const GoalContext& c, const double* ref, const double* ff, ExtendedTask& ext,
             int row0);
  void norms(const ExtendedTask& ext, int row0, double& first, double& second) const;
  void columns(const pinocchio::Model& model, int* lo, int* hi) const;
  TargetReader target() const { return PostureTarget{rows()}; }

 private:
  std::vector<int> idx_q_, idx_v_;
  std::vector<char> continuous_;
};

class ComGoalRun {
 public:
  ComGoalRun(const pinocchio::Model& model, const ComGoal& goal);
  int rows() const { return static_cast<int>(rows_.size()); }
  int ref_size() const { return 3; }
  void write(const GoalContext& c, const double* ref, const double* ff, ExtendedTask& ext,
             int row0);
  void norms(const ExtendedTask& ext, int row0, double& first, double& second) const;
  void columns(const pinocchio::Model& model, int* lo, int* hi) const;
  TargetReader target() const { return FrameTarget{true, false, rows_, false}; }

 private:
  std::vector<int> rows_;
};

using GoalRun = std::variant<FrameGoalRun, PostureGoalRun, ComGoalRun>;

// The angle x wrapped into [-pi, pi) (clik/tasks/posture_task.py's np.remainder).
double wrap_angle(double x);

// Widens [lo, hi) to the velocity columns of the joints supporting frame (its Jacobian's
// only nonzero columns); to every column when one of them is a mimic joint (whose column
// is its leader's).
void frame_columns(const pinocchio::Model& model, int frame, int& lo, int& hi);

// One run's goals, in row order.
class Goals {
 public:
  // Throws std::invalid_argument (naming the goal and field) when a goal does not fit
  // the model.
  Goals(const pinocchio::Model& model, const std::vector<GoalConfig>& goals);

  int count() const { return static_cast<int>(runs_.size()); }
  int rows() const { return rows_; }          // M = sum m_g
  int ref_size() const { return ref_size_; }  // D = sum d_g
  int rows_of(int g) const { return row_end_[g] - (g ? row_end_[g - 1] : 0); }
  int row_end(int g) const { return row_end_[g]; }  // relative to the first goal row
  int ref_size_of(int g) const { return (g + 1 < count() ? ref_at_[g + 1] : ref_size_) - ref_at_[g]; }
  // What goal g takes as a controller's target.
  TargetReader target(int g) const;
  bool needs_com() const { return com_; }
  // Frames whose placements the goals read (with repeats).
  const std::vector<int>& frames() const { return frames_; }

  // Every goal's rows into ext from row m0; ref (D) and ff (M): this sample's.
  void write(const GoalContext& c, const double* ref, const double* ff, ExtendedTask& ext,
             int m0);
  // (first, second) error norms of each goal, into norms (G, 2).
  void norms(const ExtendedTask& ext, int m0, Mat& out) const;
  // Every goal row's columns (lo, hi: rows() each), the goal's columns().
  void columns(const pinocchio::Model& model, int* lo, int* hi) const;

 private:
  std::vector<GoalRun> runs_;
  std::vector<int> row_end_, ref_at_, frames_;
  int rows_ = 0, ref_size_ = 0;
  bool com_ = false;
};

}  // namespace clik
