// Checks at the engine's boundary. Every value Python hands over is checked once, when a
// config, a run or a solver is built, or a chunk is handed to a run: never per sample.
// A failed check throws std::invalid_argument (Python: ValueError) whose message names
// the field and what was expected. The public API (clik/) checks first and raises an
// InputError naming the user's field; these checks keep the engine safe from any caller.
#pragma once

#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>

#include <pinocchio/multibody/geometry.hpp>
#include <pinocchio/multibody/model.hpp>

namespace clik {

// Throws std::invalid_argument(message) unless ok.
inline void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument(message);
}
// The same for a fixed message: its std::string made only when thrown (no allocation on a
// path that runs at every tick).
inline void require(bool ok, const char* message) {
  if (!ok) throw std::invalid_argument(message);
}

inline bool finite_positive(double x) { return std::isfinite(x) && x > 0.0; }
inline bool finite_nonnegative(double x) { return std::isfinite(x) && x >= 0.0; }

// A kind's gain [1/s]: none (the law's), or finite and > 0.
inline void require_gain(const std::optional<double>& gain, const std::string& who) {
  require(!gain || finite_positive(*gain), who + ": gain a finite number > 0 [1/s], or None");
}

// Largest window of the stop checks, in samples: window / dt is rounded to an integer
// (Python's round) and must stay exactly representable (2^53) and within a long.
constexpr double MAX_WINDOW_SAMPLES = 9007199254740992.0;

// A time window [s] of the stop checks: finite, > 0, at most MAX_WINDOW_SAMPLES samples of dt.
inline void require_window(double window, double dt, const std::string& field) {
  require(finite_positive(window) && window / dt <= MAX_WINDOW_SAMPLES,
          "StopConfig: " + field + " a finite time > 0 [s] of at most 2^53 samples of dt");
}

// What a run or a solver assumes of the pin.Model it borrows: its sizes. A model changed
// afterwards (addJoint, addFrame, ...) would make the engine read and write past its
// vectors, so each call into a built run or solver compares them first.
struct ModelShape {
  int nq = 0, nv = 0, njoints = 0, nframes = 0;

  static ModelShape of(const pinocchio::Model& model) {
    return {model.nq, model.nv, model.njoints, static_cast<int>(model.nframes)};
  }

  bool operator==(const ModelShape& o) const {
    return nq == o.nq && nv == o.nv && njoints == o.njoints && nframes == o.nframes;
  }

  std::string describe() const {
    return "nq " + std::to_string(nq) + ", nv " + std::to_string(nv) + ", njoints " +
           std::to_string(njoints) + ", nframes " + std::to_string(nframes);
  }
};

// Throws unless `model` still has the shape `built` recorded.
inline void require_same_model(const ModelShape& built, const pinocchio::Model& model,
                               const std::string& who) {
  const ModelShape now = ModelShape::of(model);
  if (now == built) return;  // the message is built only when it is thrown (~1 us)
  require(false, who + ": the pin.Model changed after it was built (" + built.describe() +
                     " then, " + now.describe() +
                     " now): build it again on the model as it is (a new clik.Robot)");
}

// The same for a GeometryModel: its geometries and collision pairs.
struct GeometryShape {
  std::size_t ngeoms = 0, npairs = 0;

  static GeometryShape of(const pinocchio::GeometryModel& g) {
    return {g.ngeoms, g.collisionPairs.size()};
  }

  bool operator==(const GeometryShape& o) const {
    return ngeoms == o.ngeoms && npairs == o.npairs;
  }
};

}  // namespace clik
