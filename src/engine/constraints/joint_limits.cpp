// Joint-range rows (16)-(19): see joint_limits.hpp and clik/constraints/joint_limits.py.
#include "constraints/joint_limits.hpp"

#include "boundary.hpp"

#include <stdexcept>
#include <string>
#include <utility>

#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

namespace clik {

void JointRangeConfig::validate() const {
  const auto n_ = static_cast<Eigen::Index>(n());
  const bool joints = static_cast<Eigen::Index>(v_index.size()) == n_ && lower.size() == n_ &&
                      upper.size() == n_ && threshold.size() == n_ &&
                      static_cast<Eigen::Index>(joint_names.size()) == n_;
  const bool rows = static_cast<Eigen::Index>(names.size()) == 2 * n_ &&
                    row_threshold.size() == 2 * n_ && sign.size() == 2 * n_;
  if (!joints || !rows) {
    throw std::invalid_argument(
        "JointRangeConfig: v_index, lower, upper, threshold and joint_names need one entry per "
        "limited joint (n = len(q_index) = " + std::to_string(n()) + "), names, row_threshold "
        "and sign one per row (2n)");
  }
  for (Eigen::Index i = 0; i < n_; ++i) {
    require(std::isfinite(lower[i]) && std::isfinite(upper[i]) && lower[i] < upper[i] &&
                finite_positive(threshold[i]),
            "JointRangeConfig: joint " + joint_names[static_cast<std::size_t>(i)] +
                ": finite limits, lower < upper, and a finite threshold > 0");
  }
  for (Eigen::Index i = 0; i < 2 * n_; ++i) {
    require(finite_positive(row_threshold[i]) && (sign[i] == 1.0 || sign[i] == -1.0),
            "JointRangeConfig: row_threshold finite > 0 and sign +1 or -1, per row");
  }
  require_gain(gain, "JointRangeConfig");
}

void JointRangeConfig::check(const pinocchio::Model& model, const SceneConfig*) const {
  for (int i = 0; i < n(); ++i) {
    if (q_index[i] < 0 || q_index[i] >= model.nq || v_index[i] < 0 || v_index[i] >= model.nv) {
      throw std::invalid_argument("JointRangeConfig: joint " + joint_names[i] +
                                  ": q_index or v_index outside the robot's model");
    }
  }
}

void JointRangeConfig::evaluate(const Eigen::Ref<const Vec>& q, Eigen::Ref<Vec> e) const {
  // The same operations as the numpy version: e = thr - d, d = q - lower or
  // -(q + (-upper)) = upper - q (both exact rewrites in IEEE arithmetic).
  const int n_ = n();
  for (int i = 0; i < n_; ++i) {
    const double qi = q[q_index[i]];
    e[i] = row_threshold[i] - (qi - lower[i]);
    e[n_ + i] = row_threshold[n_ + i] - (upper[i] - qi);
  }
}

JointRange::JointRange(const JointRangeConfig& config, const KindSetup& setup)
    : cfg_(config), slot_(setup.slot), e_(Vec::Zero(2 * config.n())) {}

void JointRange::names(std::vector<std::string>& out) {
  base_ = static_cast<int>(out.size());
  out.insert(out.end(), cfg_.names.begin(), cfg_.names.end());
}

// JointRun.evaluate: the rows' errors (17), behind the certificate.
void JointRange::evaluate(Sample& s, std::vector<Candidate>& out) {
  if (s.dq_abs != nullptr && s.dq_abs->size()) joint_slack_ -= s.dq_abs->maxCoeff();
  bool joint_active = false;
  for (const Candidate& c : s.active) joint_active = joint_active || c.slot == slot_;
  if (joint_slack_ > 0.0 && !joint_active) return;
  cfg_.evaluate(s.q, e_);
  joint_slack_ = e_.size() ? -e_.maxCoeff() : INF;
  const Vec& thr = cfg_.row_threshold;
  for (int i = 0; i < static_cast<int>(e_.size()); ++i) {
    const double e = e_[i];
    if (e > -thr[i] && (e > 0.0 || s.is_active[base_ + i])) {
      Candidate c;
      c.key = base_ + i;
      c.slot = slot_;
      c.item = i;
      c.error = e;
      c.scale = c.threshold = thr[i];
      out.push_back(c);
    }
  }
}

void JointRange::row(Sample&, Candidate& c, Eigen::Ref<Eigen::RowVectorXd> row) {
  cfg_.row(c.item, row);
  c.feed = 0.0;
}

void JointRangeConfig::bind(nanobind::module_& m) {
  namespace nb = nanobind;
  nb::class_<JointRangeConfig>(m, "JointRangeConfig",
                               "Joint-range rows (16)-(19): clik.constraints.JointLimits.")
      .def(
          "__init__",
          [](JointRangeConfig* self, std::vector<int> q_index, std::vector<int> v_index,
             const Vec& lower, const Vec& upper, const Vec& threshold,
             std::vector<std::string> joint_names, std::vector<std::string> names,
             const Vec& row_threshold, const Vec& sign, std::optional<double> gain) {
            JointRangeConfig c{std::move(q_index), std::move(v_index), lower, upper, threshold,
                               std::move(joint_names), std::move(names), row_threshold, sign,
                               gain};
            c.validate();
            new (self) JointRangeConfig(std::move(c));
          },
          nb::kw_only(), nb::arg("q_index"), nb::arg("v_index"), nb::arg("lower"),
          nb::arg("upper"), nb::arg("threshold"), nb::arg("joint_names"), nb::arg("names"),
          nb::arg("row_threshold"), nb::arg("sign"), nb::arg("gain").none() = nb::none())
      .def_ro("q_index", &JointRangeConfig::q_index)
      .def_ro("v_index", &JointRangeConfig::v_index)
      .def_ro("lower", &JointRangeConfig::lower)
      .def_ro("upper", &JointRangeConfig::upper)
      .def_ro("threshold", &JointRangeConfig::threshold)
      .def_ro("joint_names", &JointRangeConfig::joint_names)
      .def_ro("names", &JointRangeConfig::names)
      .def_ro("row_threshold", &JointRangeConfig::row_threshold)
      .def_ro("sign", &JointRangeConfig::sign)
      .def_ro("gain", &JointRangeConfig::gain);
}

}  // namespace clik
