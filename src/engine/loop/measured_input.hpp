// The measured joints at the ticker's boundary (loop/bind_ticker.cpp): q_measured and
// qdot_measured copied from the caller's objects into Measured's buffers with the checks,
// in the same order and words, of clik/control/measured.py's MeasuredJoints.stage (shape,
// finite, unit rotations), and this session's record of them (MeasuredJoints.keep).
#pragma once

#include <memory>
#include <vector>

#include <nanobind/nanobind.h>

#include "loop/bind_record.hpp"
#include "loop/measured.hpp"
#include "types.hpp"

namespace clik {

struct MeasuredInput {
  std::unique_ptr<Measured> measured;  // the checks and (M3) (loop/measured.hpp)
  long bound_size = 0;                 // nv
  double rotation_tolerance = 0.0;
  nanobind::object q_field, qdot_field, words, velocity_words;  // their names, expectations
  std::vector<nanobind::object> rotation_words;  // what each rotation of q must be
  nanobind::object convert, refuse;  // the ticker's as_floats and clik.InputError
  // this session's record (the MeasuredJoints' arrays, written) and its count
  WrittenArray<double> rec_commanded, rec_measured, rec_qdot_measured;
  long given = 0;  // ticks given q_measured
  // this tick's: q_measured and qdot_measured given, a jump (M3), q_k before it
  bool has_q = false, has_qdot = false, jumped = false;
  Jump jump;
  Vec commanded;

  // This tick's q_measured and qdot_measured (None: not given), staged and checked;
  // qdot_measured needs q_measured.
  void stage(nanobind::handle q_in, nanobind::handle qdot_in);
  // Record slot j (NaN: none given).
  void keep(long j);

 private:
  void stage_joints(nanobind::handle value, bool velocity);
  [[noreturn]] void raise(nanobind::handle field, const std::string& expected,
                          nanobind::handle got) const;
};

}  // namespace clik
