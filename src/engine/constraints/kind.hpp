// What every kind of constraint row says, and what the shared core asks of it
// (mirrors clik/constraints/kind.py).
//
// A constraint contributes, while active, one row to the extended task (24)-(25): an
// error e_c (positive inside its threshold), a Jacobian row j_c and a feed-forward f_c.
// The core (ConstraintRun, constraint_run.hpp) owns candidates, activation and release,
// the bound on active rows (22), events and the active rows' record; it never names a
// kind. It holds one run of each kind, in the set's order, in a std::variant
// (kinds.hpp), and visits them, as Pinocchio visits its joint models: no virtual call,
// nothing allocated per sample.
//
// A kind is a pair of types:
//
//   struct XConfig {                       // its settings, bound to Python (typed)
//     using Run = X;
//     std::optional<double> gain;          // [1/s]; none: the law's default
//     bool wants_rows() const;             // may add rows (row_limit's check)
//     void check(const pinocchio::Model&, const SceneConfig*) const;  // against the robot
//     static void bind(nanobind::module_&);                           // its Python class
//   };
//   class X : public KindDefaults {         // its state for one run, allocated once
//    public:
//     X(const XConfig&, const KindSetup&);
//     void names(std::vector<std::string>& out);     // append its keys' names (in key order)
//     void evaluate(Sample&, std::vector<Candidate>& out);  // error > 0, or active
//     void row(Sample&, Candidate&, Eigen::Ref<Eigen::RowVectorXd> row);  // j_c; e_c, f_c
//     const std::optional<double>& gain() const;
//     // optional (KindDefaults has them doing nothing):
//     void observe_limits(double tk, ViolationMonitor&, const std::vector<std::string>&) const;
//     void record(int j);                            // recorded sample j: all of its row
//                                                    // (a ring's slot j is written again)
//     double min_distance() const;                   // exact nearest obstacle distance [m]
//     void records(std::vector<RecordArray>& out) const;  // after the run, to Python
//   };
//
// and its place in kinds.hpp's lists.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>

#include "constraints/collision_scene.hpp"
#include "constraints/violations.hpp"
#include "tasks/extended_task.hpp"
#include "types.hpp"

namespace nanobind {
class module_;
}

namespace clik {

// A constraint is "at its threshold" when its error is below this fraction of its scale.
constexpr double AT_THRESHOLD = 1e-6;

// One constraint whose row may enter the extended task at this sample. What is
// particular to its kind (a distance, a normal, joints) stays in the kind's state,
// indexed by `item`.
struct Candidate {
  int key = -1;            // its name: ConstraintRun::name(key)
  int slot = -1;           // the kind that offered it: its index among the run's kinds
  int item = -1;           // the kind's own index (a joint row, a pair, ...)
  double error = 0.0;      // positive inside the threshold [m, rad, m^2 or m^p]
  double scale = 1.0;      // the threshold in the error's unit (activation order, hysteresis)
  double threshold = 0.0;  // d_o, d_q [m or rad] or w_min [m^p]
  double feed = 0.0;       // feed-forward f_c of its row (14), set with the row
  bool has_witness = false;  // a distance row: the points it is measured between
  Vec3 point_a = Vec3::Zero(), point_b = Vec3::Zero();  // on the link; obstacle or other link
};

// What a kind's run is made with, once per run.
struct KindSetup {
  const pinocchio::Model& model;  // the robot (outlives the run)
  int slot;                       // the kind's index among the run's kinds
  int m;                          // task rows of every goal: the constraint rows' offset
  int task_m;                     // the primary task's rows 0..task_m (its frame, task_rows)
  const Clock& t;                 // the run's times [s]
  int n_rec;                      // recorded samples
  int frame;                      // the task's frame (-1: none given)
  const std::vector<int>& task_rows;  // the task's rows among (x, y, z, rx, ry, rz)
  double monitor_margin;          // distances evaluated exactly within threshold + margin [m]
  CollisionScene* scene;          // the set's collision scene, shared by the kinds (or null)

  double dt() const { return t.size() > 1 ? t[1] - t[0] : 0.0; }
};

// The shared collision scene at one sample: its geometry placed at most once, by the
// first kind that asks.
class ScenePlacement {
 public:
  ScenePlacement(CollisionScene* scene, const pinocchio::Model& model,
                 const pinocchio::Data& data, double t)
      : scene_(scene), model_(model), data_(data), t_(t) {}

  // The scene for this sample: each geometry is placed when a distance first asks for it.
  CollisionScene& placed() {
    if (!placed_) {
      scene_->begin_sample(data_, t_);
      placed_ = true;
    }
    return *scene_;
  }

  // The scene as it is (its joints' bounding spheres need no placement).
  CollisionScene& unplaced() { return *scene_; }

 private:
  CollisionScene* scene_;
  const pinocchio::Model& model_;
  const pinocchio::Data& data_;
  double t_;
  bool placed_ = false;
};

// What the kinds see at one sample (filled by the core).
struct Sample {
  double tk;                          // [s]
  const Eigen::Ref<const Vec>& q;     // configuration (joint Jacobians computed at it)
  const pinocchio::Model& model;
  pinocchio::Data& data;              // kinematics and joint Jacobians at q
  const Vec* dq_abs;                  // |dq| since the previous sample (nv); null at the first
  const ExtendedTask& ext;            // its task rows 0..m are written (J, e, ff)
  int m;                              // task rows of every goal (constraint rows follow)
  int task_m;                         // the primary task's rows 0..task_m
  bool exact;                         // this sample is recorded: distances made exact
  const std::vector<char>& is_active; // by key
  const std::vector<Candidate>& active;  // the active constraints, in row order
  ScenePlacement& scene;
};

// A kind's record after the run, copied into a numpy array (or a list) for Python.
struct RecordArray {
  enum class Type { f64, i16, i32 };
  std::string name;
  Type type = Type::f64;
  const void* data = nullptr;  // row-major
  std::vector<std::size_t> shape;
  bool per_sample = false;  // the first dimension is the recorded samples (cut to those kept)
  bool as_list = false;     // a list of ints (1-D, i32)
};

struct CloudConfig;  // constraints/cloud_query.hpp

// The optional parts of a kind, doing nothing: a kind derives from it and hides
// (same name, same signature) what it has.
struct KindDefaults {
  // An obstacle moved by a controller (named; pose at time tk [s], velocity): whether
  // this kind has it (the obstacle kind does).
  bool move_obstacle(const std::string&, const Vec3&, const Vec3&, const Mat3&, double) {
    return false;
  }
  // A cloud replaced by a controller (named): whether this kind has it (the cloud kind does).
  bool replace_cloud(const CloudConfig&) { return false; }
  void observe_limits(double, ViolationMonitor&, const std::vector<std::string>&) const {}
  void record(int) {}
  double min_distance() const { return INF; }
  void records(std::vector<RecordArray>&) const {}
};

}  // namespace clik
