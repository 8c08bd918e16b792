// What every kind of task (a run's goal after the primary frame task) provides, stated
// once (mirrors clik/tasks/kind.py; the kinds are listed in tasks/task_kinds.hpp).
//
// A goal kind is a config type, bound to Python (`_engine.FrameGoal`, ...), and a run
// type, its state for one run, allocated once:
//
//   struct X {
//     using Run = XRun;
//     static void bind(nanobind::module_& m);   // its Python class
//   };
//   struct XRun {
//     XRun(const pinocchio::Model&, const X&);  // throws std::invalid_argument
//     int rows() const;       // m_g
//     int ref_size() const;   // d_g: doubles of reference per sample
//     int ff_size() const;    // f_g: doubles of feed-forward per sample (the rows', or the
//                             //      reference's velocity when the rows' depend on q)
//     // error, Jacobian rows (rows, nv) and feed-forward into the extended task at row0;
//     // data: joint Jacobians, frame placements (frames()) and the centre of mass
//     // (needs_com()) at q
//     void write(const GoalContext&, const double* ref, const double* ff,
//                ExtendedTask& ext, int row0);
//     void norms(const ExtendedTask& ext, int row0, double& first, double& second) const;
//     // where each row of its Jacobian may not be zero: [lo[i], hi[i]) (law (10)'s sums)
//     void columns(const pinocchio::Model&, int* lo, int* hi) const;
//     TargetReader target() const;               // a controller's target (tasks/targets.hpp)
//     void frames(std::vector<int>& out) const;  // the frames whose placements it reads
//     bool needs_com() const;                    // whether it reads the centre of mass
//   };
//
// Goals (tasks/goals.hpp) visits the kinds' std::variant: no virtual call, nothing
// allocated per sample, no kind named.
#pragma once

#include <string>
#include <vector>

#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>

#include "tasks/extended_task.hpp"
#include "tasks/targets.hpp"
#include "types.hpp"

namespace clik {

// What the goals read at one sample.
struct GoalContext {
  const pinocchio::Model& model;
  pinocchio::Data& data;  // getFrameJacobian reads it through a non-const reference
  const Vec& q;
};

// Throws std::invalid_argument unless rows are 1 to n distinct indices among 0..n-1.
void check_rows(const std::vector<int>& rows, int n, const std::string& who);
// Throws std::invalid_argument unless frame is a frame index of the model.
void check_frame(const pinocchio::Model& model, int frame, const std::string& who);

// The angle x wrapped into [-pi, pi) (clik/tasks/posture_task.py's np.remainder).
double wrap_angle(double x);

// Widens [lo, hi) to the velocity columns of the joints supporting frame (its Jacobian's
// only nonzero columns); to every column when one of them is a mimic joint (whose column
// is its leader's).
void frame_columns(const pinocchio::Model& model, int frame, int& lo, int& hi);

}  // namespace clik
