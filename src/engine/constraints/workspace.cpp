// Workspace box (W1)-(W2): see workspace.hpp and clik/constraints/workspace.py.
#include "constraints/workspace.hpp"

#include "boundary.hpp"

#include <stdexcept>

#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>
#include <pinocchio/algorithm/frames.hpp>

namespace clik {

void WorkspaceConfig::check(const pinocchio::Model& model, const SceneConfig*) const {
  if (frame < 0 || frame >= static_cast<int>(model.nframes)) {
    throw std::invalid_argument("WorkspaceConfig: the frame is not in the model");
  }
}

Workspace::Workspace(const WorkspaceConfig& config, const KindSetup& setup)
    : cfg_(config), slot_(setup.slot), J_(pinocchio::Data::Matrix6x::Zero(6, setup.model.nv)) {}

void Workspace::names(std::vector<std::string>& out) {
  base_ = static_cast<int>(out.size());
  for (const std::string& key : cfg_.keys) out.push_back(key);
}

// WorkspaceRun.evaluate: the walls' errors (W1), candidates inside their band or active.
void Workspace::evaluate(Sample& s, std::vector<Candidate>& out) {
  const auto frame = static_cast<pinocchio::FrameIndex>(cfg_.frame);
  const Vec3 p = pinocchio::updateFramePlacement(s.model, s.data, frame).translation();
  d_.head<3>() = p - cfg_.lower;
  d_.tail<3>() = cfg_.upper - p;
  const double thr = cfg_.threshold;
  for (int i = 0; i < 6; ++i) {
    const double error = thr - d_[i];
    if (error > 0.0 || s.is_active[base_ + i]) {
      Candidate c;
      c.key = base_ + i;
      c.slot = slot_;
      c.item = i;
      c.error = error;
      c.scale = c.threshold = thr;
      out.push_back(c);
    }
  }
}

// WorkspaceRun.row: (W2), +- the frame's linear Jacobian row along the wall's axis.
void Workspace::row(Sample& s, Candidate& c, Eigen::Ref<Eigen::RowVectorXd> row) {
  J_.setZero();
  pinocchio::getFrameJacobian(s.model, s.data, static_cast<pinocchio::FrameIndex>(cfg_.frame),
                              pinocchio::LOCAL_WORLD_ALIGNED, J_);
  const double sign = c.item < 3 ? 1.0 : -1.0;
  row = sign * J_.row(c.item % 3);
  c.feed = 0.0;
}

void Workspace::observe_limits(double tk, ViolationMonitor& monitor,
                               const std::vector<std::string>& names) const {
  for (int i = 0; i < 6; ++i) {
    if (d_[i] < 0.0) monitor.observe_excursion(tk, names[base_ + i], "length", -d_[i]);
  }
}

void WorkspaceConfig::bind(nanobind::module_& m) {
  namespace nb = nanobind;
  nb::class_<WorkspaceConfig>(m, "WorkspaceConfig",
                              "A workspace box (W1)-(W2): frame, lower, upper [m], threshold.")
      .def(
          "__init__",
          [](WorkspaceConfig* self, int frame, const Vec3& lower, const Vec3& upper,
             double threshold, std::vector<std::string> keys, std::optional<double> gain) {
            if (!(lower.allFinite() && upper.allFinite() && (lower.array() < upper.array()).all())) {
              throw std::invalid_argument("WorkspaceConfig: finite corners, lower < upper");
            }
            if (!(std::isfinite(threshold) && threshold > 0.0)) {
              throw std::invalid_argument("WorkspaceConfig: a positive threshold");
            }
            if (keys.size() != 6) throw std::invalid_argument("WorkspaceConfig: six keys");
            require_gain(gain, "WorkspaceConfig");
            new (self) WorkspaceConfig{frame, lower, upper, threshold, std::move(keys), gain};
          },
          nb::kw_only(), nb::arg("frame"), nb::arg("lower"), nb::arg("upper"),
          nb::arg("threshold"), nb::arg("keys"), nb::arg("gain").none() = nb::none())
      .def_ro("frame", &WorkspaceConfig::frame)
      .def_ro("threshold", &WorkspaceConfig::threshold)
      .def_ro("keys", &WorkspaceConfig::keys)
      .def_ro("gain", &WorkspaceConfig::gain);
}

}  // namespace clik
