// Helpers of the kinds' config bindings (each kind's bind()).
#pragma once

#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>

#include <nanobind/nanobind.h>
#include <nanobind/stl/optional.h>

#include "boundary.hpp"

namespace clik {

// A config made of a threshold and an optional gain: `name(*, threshold, gain=None)`,
// the threshold positive and finite (std::invalid_argument: ValueError).
template <typename Config>
void bind_threshold_config(nanobind::module_& m, const char* name, const char* doc) {
  namespace nb = nanobind;
  const std::string what = name;
  nb::class_<Config>(m, name, doc)
      .def(
          "__init__",
          [what](Config* self, double threshold, std::optional<double> gain) {
            if (!(std::isfinite(threshold) && threshold > 0.0)) {
              throw std::invalid_argument(what + ": a positive threshold");
            }
            require_gain(gain, what);
            new (self) Config{threshold, gain};
          },
          nb::kw_only(), nb::arg("threshold"), nb::arg("gain").none() = nb::none())
      .def_ro("threshold", &Config::threshold)
      .def_ro("gain", &Config::gain);
}

}  // namespace clik
