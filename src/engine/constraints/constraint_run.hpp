// One run's constraint state: candidates, activation, rows, release, records
// (mirrors clik/constraints/constraint_run.py, its specification).
//
// Interface for the tracking loop
// -------------------------------
// Set-up, once per run (nothing of it is shared between runs):
//
//   ConstraintConfig cfg = ...;  // from the Python ConstraintSet: `_engine.ConstraintConfig
//                                // .from_set(cset)` (bind_constraints.cpp); see constraint_set.hpp
//   int limit = cfg.row_limit(m, law);        // rows = m + limit for ExtendedTask and Law
//   ConstraintRun crun(cfg, model, m, law, alpha, t, n_rec, frame, task_rows);
//
//   cfg is copied (the run keeps it; its `owner` keeps the Python GeometryModel alive);
//   `model` (the robot's pinocchio::Model, cset.robot.model) must outlive the run; t is the
//   run's time grid (t[k] is sample k's time, dt = t[1] - t[0]); n_rec the recorded
//   samples (Recorder.capacity); alpha the task's largest gain [1/s]; frame and task_rows
//   the task's frame and rows among (x, y, z, rx, ry, rz) (needed by the dexterity row).
//
// Per sample k, after the loop computed pinocchio::computeJointJacobians(model, data, q)
// (data.oMi and data.J at q; the frame placement is the loop's business) and wrote the
// task rows 0..m of `ext` (J, e, ff; K set at construction; the dexterity row reads J):
//
//   int v = crun.update(k, q, data, ext, law, exact);  // exact = this sample is recorded
//   int r = m + v;                                     // the law runs on rows 0..r
//
//   update writes rows m..m+v of ext (J, e, K, ff) and, under the projection rule, may run
//   `law` on ext (law.velocity(ext, r', qdot) with r' < m + v). It allocates nothing in
//   steady state (events aside: a string is made only when accessors are called).
//   After update:
//     crun.min_distance                  exact nearest obstacle distance [m] (inf: none exact)
//     crun.dist_o[o], crun.exact_o[o]    per obstacle: nearest distance (exact when exact_o),
//     crun.link_o[o]                     and its link geometry (cfg.link_labels[link_o[o]])
//     crun.self_penetrations             (key, distance < 0) of link pairs evaluated this sample
//     crun.manipulability                w (D1) of the task rows (NaN without a dexterity row)
//   For the violation monitor (tracking.py observe_limits):
//     if min_distance < 0: for o with dist_o[o] < 0: key cfg.pair_name(link_o[o], o)
//     for (key, d) in self_penetrations: crun.name(key)
//   When the sample is recorded in slot j: crun.record(j).
//
// After the run, what ConstraintRun.finish puts in the result (bind_constraints.cpp's
// `constraint_records(crun, n_rec)` builds exactly that as Python objects):
//   events()          {t (rounded to 9 decimals as Python's round), key, action}
//   code_keys()       the key of each code used in rec_active (in code order): constraint_names
//   rec_active(), rec_witness(), rec_dist(), rec_link()   per recorded slot
//   run_min(), run_min_link() (link geometry or -1), run_min_t()   per obstacle
//   skipped_names(), active_names(), active()
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>

#include "constraints/collision_scene.hpp"
#include "constraints/constraint_set.hpp"
#include "extended_task.hpp"
#include "laws.hpp"
#include "types.hpp"

namespace clik {

// A constraint is "at its threshold" when its error is below this fraction of its scale.
constexpr double AT_THRESHOLD = 1e-6;

enum class ConstraintKind : std::uint8_t { joint, obstacle, self, dexterity };

// One constraint whose row may enter the extended task at this sample (Candidate).
// `key` names it: ConstraintRun::name(key) is joint:<joint>:lower|upper,
// obstacle:<obstacle>:<link>, self:<link a>:<link b> or dexterity.
struct Candidate {
  int key = -1;
  ConstraintKind kind = ConstraintKind::joint;
  double error = 0.0;      // positive inside the threshold [m, rad, m^2 or m^p]
  double scale = 1.0;      // the threshold in the error's unit
  double threshold = 0.0;  // d_o, d_q [m or rad] or w_min [m^p]
  double feed = 0.0;       // feed-forward (14)
  int index = -1;          // joint-range row (joint rows)
  int joint = -1, joint_b = -1;  // parent joints of the witness points
  double distance = std::numeric_limits<double>::infinity();  // signed [m]
  Vec3 point_a = Vec3::Zero(), point_b = Vec3::Zero();  // on the link; obstacle or other link
  Vec3 normal = Vec3::Zero();  // coal's, from a toward b
  int obstacle = -1;           // obstacle rows
  int link = -1;               // link geometry (obstacle rows: the pair (link, obstacle))
};

enum class EventAction : std::uint8_t { activate, release, skipped };
const char* action_name(EventAction action);

struct Event {
  double t;  // [s], rounded to 9 decimals as round(t, 9) in Python
  int key;
  EventAction action;
};

class ConstraintRun {
 public:
  // Throws std::invalid_argument for a dexterity row without the task's frame and rows.
  ConstraintRun(const ConstraintConfig& config, const pinocchio::Model& model, int m, LawKind law,
                double alpha, const TimesView& t, int n_rec, int frame = -1,
                std::vector<int> task_rows = {});
  // The scene points into the run's own copy of the config: neither copied nor moved.
  ConstraintRun(const ConstraintRun&) = delete;
  ConstraintRun& operator=(const ConstraintRun&) = delete;

  // Evaluate, activate, fill the active rows into ext (rows m .. m + v) and release;
  // returns v. data: kinematics and joint Jacobians at q (computeJointJacobians).
  // exact: make every obstacle's nearest distance exact (a recorded sample).
  int update(int k, const Eigen::Ref<const Vec>& q, pinocchio::Data& data, ExtendedTask& ext,
             Law& law, bool exact);

  // Keep this sample's distances, active set and witness points in slot j.
  void record(int j);

  // -- state after update ----------------------------------------------------------
  double min_distance = std::numeric_limits<double>::infinity();
  Vec dist_o;                       // (n_obs) nearest link distance (a lower bound unless exact_o)
  std::vector<char> exact_o;        // (n_obs)
  Eigen::VectorXi link_o;           // (n_obs) link geometry of dist_o, -1 before the first
  std::vector<std::pair<int, double>> self_penetrations;  // (key, distance < 0)
  double manipulability = std::numeric_limits<double>::quiet_NaN();  // w (D1) [m^p]

  // -- names and results -----------------------------------------------------------
  int limit() const { return limit_; }
  int n_keys() const { return static_cast<int>(names_.size()); }
  const std::string& name(int key) const { return names_[key]; }
  const ConstraintConfig& config() const { return cfg_; }
  const std::vector<Candidate>& active() const { return active_; }
  std::vector<std::string> active_names() const;
  // Constraints violated that found no free row, sorted, unique (skipped_names).
  std::vector<std::string> skipped_names() const;
  const std::vector<Event>& events() const { return events_; }
  const std::vector<int>& code_keys() const { return code_keys_; }
  int slots() const { return slots_; }
  const Mat& rec_dist() const { return rec_dist_; }  // (n_rec, n_obs), inf where unset
  const Eigen::Matrix<std::int16_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>& rec_link()
      const {
    return rec_link_;  // (n_rec, n_obs), -1 where unset
  }
  const Eigen::Matrix<std::int32_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>& rec_active()
      const {
    return rec_active_;  // (n_rec, slots) codes, -1 where unset
  }
  const Mat& rec_witness() const { return rec_witness_; }  // (n_rec, slots * 6): [a xyz, b xyz]
  const Vec& run_min() const { return run_min_; }          // (n_obs) inf: never exact
  const std::vector<int>& run_min_link() const { return run_min_link_; }  // -1: none
  const Vec& run_min_t() const { return run_min_t_; }

 private:
  void mark_active();
  void evaluate(double tk, const Eigen::Ref<const Vec>& q, pinocchio::Data& data, bool exact);
  void evaluate_joints(const Eigen::Ref<const Vec>& q);
  void evaluate_obstacles(double tk, pinocchio::Data& data, bool exact);
  void obstacle_candidate(int i, int o, Candidate& c);
  void evaluate_self(double tk, pinocchio::Data& data);
  void evaluate_dexterity(const ExtendedTask& ext);
  void place(double tk, const pinocchio::Data& data);
  void refresh_active(double tk);
  void activate(double tk);
  double gain(ConstraintKind kind, double row_norm2) const;
  int fill_rows(pinocchio::Data& data, ExtendedTask& ext);
  int project_release(double tk, ExtendedTask& ext, Law& law, int v);
  void event(double tk, int key, EventAction action);

  const ConstraintConfig cfg_;
  const pinocchio::Model& model_;
  int m_;
  LawKind law_;
  double alpha_;
  int limit_;
  TimesView t_;
  int n_obs_, n_links_, n_self_, n_joint_rows_;
  int obstacle_base_, self_base_;  // first key of the obstacle pairs and of the link pairs
  int dexterity_key_ = -1;         // the dexterity row's key (after the link pairs)
  std::vector<std::string> names_;
  std::optional<CollisionScene> scene_;
  std::optional<DexterityRow> dex_;
  bool placed_ = false;

  // candidates and the active set (buffers at their largest sizes)
  std::vector<Candidate> cand_, active_, still_;
  std::vector<int> fresh_, cur_index_, marked_;
  std::vector<char> is_active_, skipped_, in_fresh_;
  std::vector<int> skipped_list_;
  std::vector<std::pair<int, int>> todo_;
  std::vector<int> close_;
  Vec qdot_;

  // certificates
  Vec q_prev_, dq_;
  bool has_prev_ = false, dq_valid_ = false;
  Vec joint_e_;
  double joint_slack_ = -1.0;  // unknown: evaluate at the first sample
  Eigen::MatrixXd lb_;         // (n_links, n_obs) distance lower bounds, -inf at the start
                               // (column-major: an obstacle's column is contiguous)
  std::vector<char> evaluated_;  // (n_links * n_obs), row-major
  Vec rho_dq_, obs_step_, thr_o_, margin_o_;
  bool has_obs_step_ = false;
  PairDistance pd_;
  pinocchio::Data::Matrix6x J6a_, J6b_;
  Eigen::Matrix<double, 3, Eigen::Dynamic> Jp_;

  // records
  std::vector<Event> events_;
  std::vector<int> code_of_key_, code_keys_;
  int slots_;
  Mat rec_dist_;
  Eigen::Matrix<std::int16_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rec_link_;
  Eigen::Matrix<std::int32_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rec_active_;
  Mat rec_witness_;
  Vec run_min_, run_min_t_;
  std::vector<int> run_min_link_;
};

}  // namespace clik
