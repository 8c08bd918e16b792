#include "model/model_bridge.hpp"

#include <boost/python.hpp>

#include <stdexcept>

namespace clik {

namespace {

template <typename T>
T& borrow(PyObject* obj, const char* what) {
  namespace bp = boost::python;
  bp::object handle{bp::handle<>(bp::borrowed(obj))};
  bp::extract<T&> extracted(handle);
  if (!extracted.check()) {
    throw std::invalid_argument(std::string("expected a ") + what);
  }
  return extracted();
}

}  // namespace

pinocchio::Model& borrow_model(PyObject* obj) { return borrow<pinocchio::Model>(obj, "pin.Model"); }

pinocchio::GeometryModel& borrow_geometry_model(PyObject* obj) {
  return borrow<pinocchio::GeometryModel>(obj, "pin.GeometryModel");
}

std::shared_ptr<void> hold(PyObject* obj) {
  Py_INCREF(obj);
  return std::shared_ptr<void>(obj, [](void* p) {
    const PyGILState_STATE gil = PyGILState_Ensure();
    Py_DECREF(static_cast<PyObject*>(p));
    PyGILState_Release(gil);
  });
}

}  // namespace clik
