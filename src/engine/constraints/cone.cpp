// Tool axis cone (C1)-(C3): see cone.hpp and clik/constraints/cone.py.
#include "constraints/cone.hpp"

#include "boundary.hpp"

#include <cmath>
#include <stdexcept>

#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <pinocchio/algorithm/frames.hpp>

namespace clik {

double cone_angle(const Vec3& a, const Vec3& u, Vec3& n) {
  const Vec3 cross = a.cross(u);
  const double s = cross.norm();
  const double theta = std::atan2(s, a.dot(u));
  if (s > PARALLEL_SINE) {
    n = cross / s;
  } else {  // a = +-u: any normal is a gradient
    Eigen::Index least = 0;
    a.cwiseAbs().minCoeff(&least);
    n = a.cross(Vec3::Unit(least));
    n /= n.norm();
  }
  return theta;
}

void ConeConfig::check(const pinocchio::Model& model, const SceneConfig*) const {
  if (frame < 0 || frame >= static_cast<int>(model.nframes)) {
    throw std::invalid_argument("ConeConfig: the frame is not in the model");
  }
}

Cone::Cone(const ConeConfig& config, const KindSetup& setup)
    : cfg_(config), slot_(setup.slot), J_(pinocchio::Data::Matrix6x::Zero(6, setup.model.nv)) {}

void Cone::names(std::vector<std::string>& out) {
  base_ = static_cast<int>(out.size());
  out.push_back(cfg_.key);
}

// ConeRun.evaluate: the error (C2), a candidate inside the band or active.
void Cone::evaluate(Sample& s, std::vector<Candidate>& out) {
  const auto frame = static_cast<pinocchio::FrameIndex>(cfg_.frame);
  const pinocchio::SE3& placement = pinocchio::updateFramePlacement(s.model, s.data, frame);
  const Vec3 a = placement.rotation() * cfg_.axis;
  theta_ = cone_angle(a, cfg_.direction, n_);
  const double error = cfg_.threshold - (cfg_.angle - theta_);
  if (error > 0.0 || s.is_active[base_]) {
    Candidate c;
    c.key = base_;
    c.slot = slot_;
    c.item = 0;
    c.error = error;
    c.scale = c.threshold = cfg_.threshold;
    out.push_back(c);
  }
}

// ConeRun.row: (C3), n^T J_w.
void Cone::row(Sample& s, Candidate& c, Eigen::Ref<Eigen::RowVectorXd> row) {
  J_.setZero();
  pinocchio::getFrameJacobian(s.model, s.data, static_cast<pinocchio::FrameIndex>(cfg_.frame),
                              pinocchio::LOCAL_WORLD_ALIGNED, J_);
  row.noalias() = n_.transpose() * J_.bottomRows<3>();
  c.feed = 0.0;
}

void Cone::observe_limits(double tk, ViolationMonitor& monitor,
                          const std::vector<std::string>& names) const {
  const double excess = theta_ - cfg_.angle;
  if (excess > 0.0) monitor.observe_excursion(tk, names[base_], "angle", excess);
}

void ConeConfig::bind(nanobind::module_& m) {
  namespace nb = nanobind;
  nb::class_<ConeConfig>(m, "ConeConfig",
                         "A tool axis cone (C1)-(C3): frame, axis, direction, angle, threshold.")
      .def(
          "__init__",
          [](ConeConfig* self, int frame, const Vec3& axis, const Vec3& direction, double angle,
             double threshold, std::string key, std::optional<double> gain) {
            if (!(axis.allFinite() && direction.allFinite() &&
                  std::abs(axis.norm() - 1.0) < 1e-9 && std::abs(direction.norm() - 1.0) < 1e-9)) {
              throw std::invalid_argument("ConeConfig: unit axis and direction");
            }
            if (!(std::isfinite(angle) && angle > 0.0 && angle <= M_PI)) {
              throw std::invalid_argument("ConeConfig: an angle in (0, pi]");
            }
            if (!(std::isfinite(threshold) && threshold > 0.0 && threshold < angle)) {
              throw std::invalid_argument("ConeConfig: a threshold in (0, angle)");
            }
            require_gain(gain, "ConeConfig");
            new (self) ConeConfig{frame, axis, direction, angle, threshold, std::move(key), gain};
          },
          nb::kw_only(), nb::arg("frame"), nb::arg("axis"), nb::arg("direction"),
          nb::arg("angle"), nb::arg("threshold"), nb::arg("key"),
          nb::arg("gain").none() = nb::none())
      .def_ro("frame", &ConeConfig::frame)
      .def_ro("angle", &ConeConfig::angle)
      .def_ro("threshold", &ConeConfig::threshold)
      .def_ro("key", &ConeConfig::key)
      .def_ro("gain", &ConeConfig::gain);
}

}  // namespace clik
