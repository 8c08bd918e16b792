// The Python module clik._engine: hands arrays in and out, nothing per sample.
// Loaded through clik/engine.py, which checks the versions first.
#include <nanobind/nanobind.h>
#include <nanobind/stl/string.h>

#include <coal/config.hh>
#include <pinocchio/config.hpp>

#include "bindings.hpp"
#include "model/model_bridge.hpp"
#define CLIK_NUMPY_IMPORT  // NumPy's C API table, imported here once (numpy_api.hpp)
#include "numpy_api.hpp"

namespace nb = nanobind;

NB_MODULE(_engine, m) {
  m.doc() = "clik's compiled engine (load it through clik.engine)";
  if (_import_array() < 0) throw nb::python_error();
  m.attr("PINOCCHIO_VERSION") = PINOCCHIO_VERSION;
  m.attr("COAL_VERSION") = COAL_VERSION;
  m.def("model_dimensions", [](nb::handle model) {
    const pinocchio::Model& model_ref = clik::borrow_model(model.ptr());
    return nb::make_tuple(model_ref.nq, model_ref.nv);
  }, "(nq, nv) of a pin.Model, read through the model bridge.");
  clik::bind_laws(m);
  clik::bind_constraints(m);
  clik::bind_solve(m);
  clik::bind_tracking(m);
}
