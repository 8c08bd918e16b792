// A run's extra goals (issue 24): the tasks after the primary frame task, each with its
// own rows of the extended task, reference, gains and priority level (mirrors the goals of
// clik/loop/tracking.py and clik/loop/goal_rows.py). The rows of goal g follow those of
// goal g - 1, after the primary task's rows 0..m0; its reference doubles and feed-forward
// doubles follow those of goal g - 1 in each sample's goal_ref (D) and goal_ff (F).
//
// The kinds are tasks/task_kinds.hpp's; what each provides, tasks/goal_kind.hpp. This
// core visits them and names none.
#pragma once

#include <vector>

#include "tasks/task_kinds.hpp"

namespace clik {

// One run's goals, in row order.
class Goals {
 public:
  // Throws std::invalid_argument (naming the goal and field) when a goal does not fit
  // the model.
  Goals(const pinocchio::Model& model, const std::vector<GoalConfig>& goals);

  int count() const { return static_cast<int>(runs_.size()); }
  int rows() const { return rows_; }          // M = sum m_g
  int ref_size() const { return ref_size_; }  // D = sum d_g
  int ff_size() const { return ff_size_; }    // F = sum f_g
  int rows_of(int g) const { return row_end_[g] - (g ? row_end_[g - 1] : 0); }
  int row_end(int g) const { return row_end_[g]; }  // relative to the first goal row
  int ref_at(int g) const { return ref_at_[g]; }    // its first reference double
  int ff_at(int g) const { return ff_at_[g]; }      // its first feed-forward double
  bool needs_com() const { return com_; }
  // Frames whose placements the goals read (with repeats).
  const std::vector<int>& frames() const { return frames_; }
  // What goal g takes as a controller's target.
  TargetReader target(int g) const;

  // Every goal's rows into ext from row m0; ref (D) and ff (F): this sample's.
  void write(const GoalContext& c, const double* ref, const double* ff, ExtendedTask& ext,
             int m0);
  // (first, second) error norms of each goal, into norms (G, 2).
  void norms(const ExtendedTask& ext, int m0, Mat& out) const;
  // Every goal row's columns (lo, hi: rows() each), the goal's columns().
  void columns(const pinocchio::Model& model, int* lo, int* hi) const;

 private:
  std::vector<GoalRun> runs_;
  std::vector<int> row_end_, ref_at_, ff_at_, frames_;
  int rows_ = 0, ref_size_ = 0, ff_size_ = 0;
  bool com_ = false;
};

}  // namespace clik
