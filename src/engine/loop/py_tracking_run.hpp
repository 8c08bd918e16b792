// A tracking run as Python holds it (`_engine.TrackingRun`, loop/bind_tracking.cpp) and
// what the controller's ticker (loop/bind_ticker.cpp) reads of it.
#pragma once

#include <memory>
#include <optional>

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include "boundary.hpp"
#include "constraints/constraint_run.hpp"
#include "loop/bind_record.hpp"
#include "loop/tracking.hpp"

namespace clik {

template <typename T>
using In = nanobind::ndarray<const T, nanobind::c_contig, nanobind::device::cpu>;

// The stop as Python names it (clik/loop/compiled_run.py reads it): "" when none.
inline const char* stop_name(Stop s) {
  switch (s) {
    case Stop::none: return "";
    case Stop::non_finite: return "non_finite";
    case Stop::joint_step: return "joint_step";
    case Stop::unstable: return "unstable";
    case Stop::deadlock: return "deadlock";
    case Stop::stall: return "stall";
  }
  return "";
}

// A run and the Python objects whose memory it uses (kept alive with it).
struct PyTrackingRun {
  nanobind::object model;
  ModelShape built;      // the model's sizes when the run was built
  long next = 0;         // the sample the next advance() starts at
  bool stopped = false;  // never in an open run
  std::optional<In<double>> times;  // none: an open run
  RecordArrays record;
  std::unique_ptr<ConstraintRun> constraints;  // before run: it outlives the loop's use
  std::unique_ptr<TrackingRun> run;
};

void bind_ticker(nanobind::module_& m);  // loop/bind_ticker.cpp

}  // namespace clik
