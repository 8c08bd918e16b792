// Each room of the engine binds its own Python entry points (bind_*.cpp);
// bindings.cpp builds the module from them.
#pragma once

#include <nanobind/nanobind.h>

namespace clik {

void bind_laws(nanobind::module_& m);
void bind_constraints(nanobind::module_& m);
void bind_solve(nanobind::module_& m);
void bind_tracking(nanobind::module_& m);

}  // namespace clik
