// Python entry points of the laws, for the parity tests against clik/loop/laws.py.
#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <nanobind/stl/string.h>

#include "bindings.hpp"
#include "boundary.hpp"
#include "loop/laws.hpp"

namespace nb = nanobind;

namespace clik {

void bind_laws(nb::module_& m) {
  m.attr("CONDITION_RATIO") = CONDITION_RATIO;
  m.attr("STEP_BUDGET") = STEP_BUDGET;
  m.attr("RANK_TOLERANCE") = RANK_TOLERANCE;
  m.def(
      "law_velocity",
      [](const std::string& law, const Mat& J, const Vec& e, const Vec& K, const Vec& ff, int m_rows,
         double damping, double dt, double beta_max) {
        const int rows = static_cast<int>(J.rows());
        const int nv = static_cast<int>(J.cols());
        require(rows >= 1 && nv >= 1 && e.size() == rows && K.size() == rows &&
                    ff.size() == rows && m_rows >= 1 && m_rows <= rows &&
                    m_rows <= MAX_TASK_ROWS,
                "law_velocity: J (r, nv) with r, nv >= 1; e, K and ff (r,); 1 <= m <= min(r, 6)");
        require(finite_nonnegative(damping) && finite_positive(dt) && finite_positive(beta_max),
                "law_velocity: damping finite >= 0, dt and beta_max finite > 0");
        LawSettings s;
        s.kind = law_kind(law);
        s.damping = damping;
        s.dt = dt;
        s.beta_max = beta_max;
        ExtendedTask ext(m_rows, rows, nv, K.head(m_rows));
        ext.J = J;
        ext.e = e;
        ext.K = K;
        ext.ff = ff;
        Law law_(s, rows, nv);
        Vec qdot(nv);
        const double blocked = law_.velocity(ext, rows, qdot);
        return nb::make_tuple(qdot, blocked);
      },
      nb::arg("law"), nb::arg("J"), nb::arg("e"), nb::arg("K"), nb::arg("ff"), nb::arg("m"),
      nb::arg("damping"), nb::arg("dt"), nb::arg("beta_max"),
      "One evaluation of a law on an extended task (all rows active): (qdot, blocked).");
}

}  // namespace clik
