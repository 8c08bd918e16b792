// The robot's model crossing from Python: the very pinocchio::Model and
// pinocchio::GeometryModel objects the `pin` module holds, borrowed through
// Boost.Python (the binding system of `pin`), never copied or rebuilt.
#pragma once

#include <pinocchio/multibody/fwd.hpp>
#include <pinocchio/multibody/geometry.hpp>
#include <pinocchio/multibody/model.hpp>

#include <Python.h>

#include <memory>

namespace clik {

// The pinocchio::Model behind a `pin.Model` Python object; throws
// std::invalid_argument when `obj` is not one. The Python object must outlive
// the reference (the caller keeps it).
pinocchio::Model& borrow_model(PyObject* obj);

// The pinocchio::GeometryModel behind a `pin.GeometryModel` Python object.
pinocchio::GeometryModel& borrow_geometry_model(PyObject* obj);

// A strong reference to `obj`, dropped (under the GIL) when the last copy goes: keeps a
// borrowed model's Python object alive with the C++ struct that points into it.
std::shared_ptr<void> hold(PyObject* obj);

}  // namespace clik
