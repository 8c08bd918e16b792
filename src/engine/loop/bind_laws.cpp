// Python entry points of the laws, for the parity tests against clik/loop/laws.py.
#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <nanobind/stl/pair.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include "bindings.hpp"
#include "boundary.hpp"
#include "loop/laws.hpp"
#include "loop/speed_step.hpp"

namespace nb = nanobind;

namespace clik {

void bind_laws(nb::module_& m) {
  m.attr("CONDITION_RATIO") = CONDITION_RATIO;
  m.attr("STEP_BUDGET") = STEP_BUDGET;
  m.attr("RANK_TOLERANCE") = RANK_TOLERANCE;
  m.attr("GRAM_TOLERANCE") = GRAM_TOLERANCE;
  m.attr("NEGLIGIBLE") = NEGLIGIBLE;
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
  m.def(
      "levels_velocity",
      [](const Mat& J, const Vec& b_task, const std::vector<int>& ends, const Mat& C,
         const Vec& b_constraint, double damping, double dt,
         const std::vector<std::pair<int, Vec>>& objectives, bool budget_blocks) {
        const int m_rows = static_cast<int>(J.rows()), nv = static_cast<int>(J.cols());
        const int v = static_cast<int>(C.rows());
        bool ok = m_rows >= 1 && nv >= 1 && b_task.size() == m_rows && C.cols() == nv &&
                  b_constraint.size() == v && v <= nv && !ends.empty() &&
                  ends.front() >= 1 && ends.back() == m_rows;
        for (size_t l = 1; ok && l < ends.size(); ++l) ok = ends[l] > ends[l - 1];
        LevelPlan plan{ends, {}};
        for (const auto& [level, z] : objectives) {
          ok = ok && level >= 1 && level <= static_cast<int>(ends.size()) && z.size() == nv;
          plan.objective_levels.push_back(level);
        }
        require(ok,
                "levels_velocity: J (m, nv), b_task (m,), ends strictly increasing to m, C "
                "(v, nv) with v <= nv, b_constraint (v,), objectives (level in 1..L, z (nv,))");
        require(finite_nonnegative(damping) && finite_positive(dt),
                "levels_velocity: damping finite >= 0, dt finite > 0");
        LawSettings s;
        s.kind = LawKind::pseudoinverse;
        s.damping = damping;
        s.dt = dt;
        s.budget_blocks = budget_blocks;
        const int rows = m_rows + v;
        ExtendedTask ext(m_rows, rows, nv, Vec::Ones(m_rows));
        ext.J.topRows(m_rows) = J;
        ext.J.bottomRows(v) = C;
        ext.e.head(m_rows) = b_task;
        ext.e.tail(v) = b_constraint;
        ext.K.setOnes();
        ext.ff.setZero();
        Law law(s, rows, nv, m_rows, plan);
        for (size_t i = 0; i < objectives.size(); ++i) law.objective_z()[i] = objectives[i].second;
        Vec qdot(nv);
        const double blocked = law.velocity(ext, rows, qdot);
        return nb::make_tuple(qdot, law.by_levels() ? law.parts() : Mat(), blocked);
      },
      nb::arg("J"), nb::arg("b_task"), nb::arg("ends"), nb::arg("C"), nb::arg("b_constraint"),
      nb::arg("damping"), nb::arg("dt"), nb::arg("objectives"), nb::arg("budget_blocks") = true,
      "Law (10) by levels (clik/loop/levels.py's prioritized_levels): (qdot, parts, blocked); "
      "parts empty when the run would take law (10)'s one-level path.");
}

}  // namespace clik
