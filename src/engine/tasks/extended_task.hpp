// The extended task of one run, eqs. (24)-(25), as preallocated arrays
// (mirrors clik/tasks/extended_task.py). Rows 0..m are the task (J, e = x_d - x,
// gains K, feed-forward xdot_d): the primary task's rows first, then the extra goals'
// (issue 24), level by level; rows m..m+v the active constraints' rows,
// written each sample by the run's ConstraintRun. The run owns it.
#pragma once

#include <stdexcept>

#include "types.hpp"

namespace clik {

struct ExtendedTask {
  int m;     // task rows: the primary task's and the extra goals'
  int rows;  // room: task plus the most constraint rows
  int nv;
  Mat J;     // (rows, nv)
  Vec e;     // (rows)
  Vec K;     // gain per row [1/s]
  Vec ff;    // feed-forward per row: xdot_d for the task, (14) for obstacles

  ExtendedTask(int m_, int rows_, int nv_, const Vec& K_task)
      : m(m_), rows(rows_), nv(nv_), J(Mat::Zero(rows_, nv_)), e(Vec::Zero(rows_)),
        K(Vec::Zero(rows_)), ff(Vec::Zero(rows_)) {
    if (m_ < 1 || rows_ < m_ || K_task.size() != m_) {
      throw std::invalid_argument("task: at least 1 row, one gain per task row, room for them");
    }
    K.head(m) = K_task;
  }

  // K e + ff of the first r rows: what law (10) asks each row to do.
  void demand(int r, Eigen::Ref<Vec> out) const {
    out.head(r) = K.head(r).cwiseProduct(e.head(r)) + ff.head(r);
  }

  // Exchange rows a and b (Jacobian, error, gain, feed-forward).
  void swap(int a, int b) {
    J.row(a).swap(J.row(b));
    std::swap(e[a], e[b]);
    std::swap(K[a], K[b]);
    std::swap(ff[a], ff[b]);
  }
};

}  // namespace clik
