// Tool axis cone (C1)-(C3) of docs/method.md (mirrors clik/constraints/cone.py): a unit
// axis a_f fixed in a frame, a = R a_f in the world, kept within theta_max of a fixed
// unit direction u. theta = atan2(|a x u|, a . u) (C1); error e = d_c - (theta_max -
// theta) (C2); row n^T J_w, n = (a x u) / |a x u|, J_w the frame's world-aligned
// angular Jacobian (C3), no feed-forward. One row, item 0; the limit guarded is the
// cone's surface.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>

#include "constraints/kind.hpp"
#include "types.hpp"

namespace clik {

class Cone;

// Below this |a x u| the axis is along (or against) the direction: n is then normal to a
// and the world axis least along it.
constexpr double PARALLEL_SINE = 1e-12;

struct ConeConfig {
  using Run = Cone;
  int frame = -1;                    // the frame carrying the axis
  Vec3 axis = Vec3::UnitZ();         // a_f, unit, in the frame
  Vec3 direction = Vec3::UnitZ();    // u, unit, in the world
  double angle = 0.0;                // theta_max [rad]
  double threshold = 0.0;            // d_c [rad]
  std::string key;                   // cone:<name>
  std::optional<double> gain;        // [1/s]; none: the law's default

  bool wants_rows() const { return true; }
  // Throws std::invalid_argument for a frame the model does not have.
  void check(const pinocchio::Model& model, const SceneConfig*) const;
  static void bind(nanobind::module_& m);
};

// theta (C1) [rad] between unit vectors a and u, and n of (C3) (at a = -+u: the unit
// normal to a and to the world axis least along it).
double cone_angle(const Vec3& a, const Vec3& u, Vec3& n);

class Cone : public KindDefaults {
 public:
  Cone(const ConeConfig& config, const KindSetup& setup);
  void names(std::vector<std::string>& out);
  void evaluate(Sample& s, std::vector<Candidate>& out);
  void row(Sample& s, Candidate& c, Eigen::Ref<Eigen::RowVectorXd> row);
  const std::optional<double>& gain() const { return cfg_.gain; }
  // The axis outside the cone, as an angle excursion.
  void observe_limits(double tk, ViolationMonitor& monitor,
                      const std::vector<std::string>& names) const;

 private:
  ConeConfig cfg_;
  int slot_, base_ = 0;
  double theta_ = 0.0;
  Vec3 n_ = Vec3::Zero();
  pinocchio::Data::Matrix6x J_;
};

}  // namespace clik
