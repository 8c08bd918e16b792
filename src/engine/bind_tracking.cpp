// Python entry point of a tracking run (used by clik/compiled_run.py): Python
// builds the robot, the reference chunks and the record arrays; the engine
// runs the samples and writes the record in place.
#include <memory>
#include <string>
#include <vector>

#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

#include "bindings.hpp"
#include "constraints/bind_constraints.hpp"
#include "constraints/constraint_run.hpp"
#include "model_bridge.hpp"
#include "tracking.hpp"

namespace nb = nanobind;

namespace clik {

namespace {

using F64 = nb::ndarray<double, nb::c_contig, nb::device::cpu>;

const char* stop_name(Stop s) {
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

template <typename T>
T* data_of(nb::handle array) {
  if (array.is_none()) return nullptr;
  return nb::cast<nb::ndarray<T, nb::c_contig, nb::device::cpu>>(array).data();
}

// A run and the Python objects whose memory it uses (kept alive with it).
struct PyTrackingRun {
  nb::object model, recorder, times;
  std::unique_ptr<ConstraintRun> constraints;  // before run: it outlives the loop's use
  std::unique_ptr<TrackingRun> run;
};

PyTrackingRun make_run(nb::object model, int frame, std::vector<int> rows, bool has_position,
                       bool has_orientation, const std::string& law, double damping, double dt,
                       double beta_max, const Vec& K_task, int n_rows,
                       std::tuple<double, double, double, double, double, double> stop,
                       nb::object t, nb::object recorder, std::vector<int> joint_index,
                       const Vec& joint_lower, const Vec& joint_upper,
                       std::vector<std::string> joint_names, nb::handle constraints,
                       double alpha) {
  const pinocchio::Model& m = borrow_model(model.ptr());
  TaskSpec task{frame, std::move(rows), has_position, has_orientation};
  LawSettings ls{law_kind(law), damping, dt, beta_max};
  StopSettings ss;
  std::tie(ss.deadlock_window, ss.deadlock_ratio, ss.deadlock_error, ss.max_joint_step,
           ss.stall_window, ss.stall_progress) = stop;
  RecordBuffers b;
  b.N = nb::cast<long>(recorder.attr("N"));
  b.every = nb::cast<long>(recorder.attr("every"));
  b.capacity = nb::cast<long>(recorder.attr("capacity"));
  b.nq = m.nq;
  b.nv = m.nv;
  b.idx = data_of<std::intptr_t>(recorder.attr("idx"));
  b.q = data_of<double>(recorder.attr("q"));
  b.qdot = data_of<double>(recorder.attr("qdot"));
  b.qddot = data_of<double>(recorder.attr("qddot"));
  b.position = data_of<double>(recorder.attr("position"));
  b.reference = data_of<double>(recorder.attr("reference"));
  b.error = data_of<double>(recorder.attr("error"));
  b.orientation_error = data_of<double>(recorder.attr("orientation_error"));
  b.active = data_of<std::int16_t>(recorder.attr("active"));
  b.distance = data_of<double>(recorder.attr("distance"));
  b.joint_min = data_of<double>(recorder.attr("joint_min"));
  b.joint_max = data_of<double>(recorder.attr("joint_max"));
  b.qdot_prev = data_of<double>(recorder.attr("_qdot_prev"));
  JointRange joints{std::move(joint_index), joint_lower, joint_upper, std::move(joint_names)};
  // No conversion: a converted copy would die here, leaving the view dangling.
  const auto grid =
      nb::cast<nb::ndarray<const double, nb::ndim<1>, nb::c_contig, nb::device::cpu>>(t, false);
  const TimesView times(grid.data(), static_cast<Eigen::Index>(grid.shape(0)));
  PyTrackingRun out{model, recorder, t, nullptr, nullptr};
  if (!constraints.is_none()) {
    const ConstraintConfig cfg = config_from_set(constraints);
    const int m_rows = static_cast<int>(task.rows.size());
    out.constraints = std::make_unique<ConstraintRun>(cfg, m, m_rows, ls.kind, alpha, times,
                                                      static_cast<int>(b.capacity), task.frame,
                                                      task.rows);
    if (m_rows + std::max(out.constraints->limit(), 0) > n_rows) {
      throw std::invalid_argument("n_rows: fewer than the task's and the constraints' rows");
    }
  }
  out.run = std::make_unique<TrackingRun>(m, task, ls, K_task, n_rows, ss, times, b,
                                          std::move(joints), out.constraints.get());
  return out;
}

nb::tuple advance(PyTrackingRun& self, long c0, long c1, nb::handle P_d, nb::handle R_d, F64 FF,
                  nb::ndarray<bool, nb::c_contig, nb::device::cpu> at_rest,
                  F64 q) {
  Advance a;
  const double* p = data_of<double>(P_d);
  const double* r = data_of<double>(R_d);
  {
    nb::gil_scoped_release release;
    Eigen::Map<Vec> qv(q.data(), static_cast<Eigen::Index>(q.shape(0)));
    a = self.run->advance(c0, c1, p, r, FF.data(), at_rest.data(), qv);
  }
  return nb::make_tuple(a.next, stop_name(a.stop), a.k, a.r, a.err);
}

}  // namespace

void bind_tracking(nb::module_& m) {
  nb::class_<PyTrackingRun>(m, "TrackingRun")
      .def(nb::new_(&make_run), nb::arg("model"), nb::arg("frame"), nb::arg("rows"),
           nb::arg("has_position"), nb::arg("has_orientation"), nb::arg("law"),
           nb::arg("damping"), nb::arg("dt"), nb::arg("beta_max"), nb::arg("K_task"),
           nb::arg("n_rows"), nb::arg("stop"), nb::arg("t"), nb::arg("recorder"),
           nb::arg("joint_index"), nb::arg("joint_lower"), nb::arg("joint_upper"),
           nb::arg("joint_names"), nb::arg("constraints").none(), nb::arg("alpha"))
      .def("advance", &advance, nb::arg("c0"), nb::arg("c1"), nb::arg("P_d").none(),
           nb::arg("R_d").none(), nb::arg("FF"), nb::arg("at_rest"), nb::arg("q"),
           "Run samples [c0, c1): (next, stop, k, r, err); q is updated in place.")
      .def_prop_ro("max_error", [](const PyTrackingRun& s) { return s.run->max_error(); })
      .def_prop_ro("last_error", [](const PyTrackingRun& s) { return s.run->last_error(); })
      .def_prop_ro("steps", [](const PyTrackingRun& s) { return s.run->steps(); })
      .def_prop_ro("kept", [](const PyTrackingRun& s) { return s.run->kept(); })
      .def_prop_ro("qdot", [](const PyTrackingRun& s) { return Vec(s.run->qdot()); })
      .def_prop_ro("jump", [](const PyTrackingRun& s) { return s.run->checks().jump; })
      .def_prop_ro("margin", [](const PyTrackingRun& s) { return s.run->checks().margin; })
      .def_prop_ro("worst_margin",
                   [](const PyTrackingRun& s) { return s.run->checks().worst_margin; })
      .def_prop_ro("ext_J", [](const PyTrackingRun& s) { return Mat(s.run->extended().J); })
      .def_prop_ro("ext_e", [](const PyTrackingRun& s) { return Vec(s.run->extended().e); })
      .def_prop_ro("ext_K", [](const PyTrackingRun& s) { return Vec(s.run->extended().K); })
      .def_prop_ro("ext_ff", [](const PyTrackingRun& s) { return Vec(s.run->extended().ff); })
      .def("constraint_records",
           [](const PyTrackingRun& s) {
             if (!s.constraints) throw std::invalid_argument("the run has no constraints");
             nb::dict out = constraint_records(*s.constraints, static_cast<int>(s.run->kept()));
             nb::list active;
             for (const std::string& name : s.constraints->active_names()) active.append(name);
             out["active_names"] = active;
             out["limit"] = s.constraints->limit();
             return out;
           },
           "What the run's constraints recorded (see constraints/bind_constraints.hpp).")
      .def_prop_ro("violations", [](const PyTrackingRun& s) {
        nb::list out;
        for (const auto& v : s.run->monitor().records()) {
          out.append(nb::make_tuple(v.constraint, v.kind, v.t_first, v.t_last, v.worst));
        }
        return out;
      });
}

}  // namespace clik
