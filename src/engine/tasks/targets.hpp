// What a task takes as a controller's target for one tick (its accepted forms of target
// and velocity; the specification is clik/control/targets.py): each kind of task has its
// reader, which checks the numbers the Ticker copied out of the caller's objects
// (loop/py_values.hpp) and writes them as the task's one-sample reference and feed-forward.
// Nothing here touches Python: what is wrong is a Refusal (clik.InputError's expected and
// got), which the Ticker raises. loop/tick_targets.hpp reads every task of a tick.
#pragma once

#include <string>
#include <variant>
#include <vector>

namespace clik {

// Largest |R^T R - I| (entrywise) and |det R - 1| of a rotation given as a target (as
// clik.trajectory's ROTATION_TOLERANCE).
constexpr double ROTATION_TOLERANCE = 1e-6;

// A target's or a velocity's numbers, as copied from the caller's array: its shape as
// numpy gives it, its values in row-major order (only for a shape the task takes).
struct Floats {
  static constexpr int MAX_DIMS = 64;  // NumPy's NPY_MAXDIMS
  std::vector<double> values;          // room for the task's largest form, reserved once
  long shape[MAX_DIMS] = {};
  int ndim = 0;
  bool given = false;  // a velocity may be left out (None)

  bool is(long n) const { return ndim == 1 && shape[0] == n; }
  bool is(long rows, long cols) const { return ndim == 2 && shape[0] == rows && shape[1] == cols; }
};

// What is wrong with a task's target (or velocity), in clik.InputError's words: `expected`,
// and what to show as got: the shape (``shape (16,)``), the values, or a 4x4's last row.
struct Refusal {
  enum class Show { shape, values, last_row };
  bool velocity = false;
  std::string expected;
  Show show = Show::shape;
};

// A frame's pose (a frame task, in the world or relative to another frame) or a position
// (a centre of mass: pos only, no R in its reference): target a 4x4 homogeneous pose
// (row-major), a position (3,) without orientation rows, a rotation (3, 3) without position
// rows; velocity (linear, angular) (6,), or (3,) for a task with one of the two. Writes p (3)
// and R (9, row-major; the identity without orientation rows; R null: not written), and
// ff: the velocity's rows.
struct FrameTarget {
  bool pos = true, rot = true;
  std::vector<int> rows;  // among (x, y, z, rx, ry, rz)
  bool rotation_ref = true;  // its reference holds R after p (a pose: 12); false: p only (3)

  long target_size(const Floats& f) const;    // doubles to read, or -1: a form it does not take
  long velocity_size(const Floats& f) const;  // likewise (0: none given)
  std::string target_forms() const;
  std::string velocity_forms() const;
  bool read(const Floats& target, const Floats& velocity, double* p, double* R, double* ff,
            Refusal& why) const;
};

// Values (a posture's joints, a distance): target (m,), velocity (m,); one value may also
// be given as a number (shape ()). Writes ref and ff, m each.
struct ValuesTarget {
  long m = 0;
  std::string what = "joint values", unit = "rad or m";         // the target's words
  std::string rate = "joint velocities", rate_unit = "rad/s or m/s";  // the velocity's

  long target_size(const Floats& f) const { return size(f); }
  long velocity_size(const Floats& f) const { return !f.given ? 0 : size(f); }
  std::string target_forms() const { return forms(what, unit); }
  std::string velocity_forms() const { return forms(rate, rate_unit); }
  bool read(const Floats& target, const Floats& velocity, double* ref, double* ff,
            Refusal& why) const;

 private:
  long size(const Floats& f) const { return f.is(m) || (m == 1 && f.ndim == 0) ? m : -1; }
  std::string forms(const std::string& words, const std::string& in) const;
};

using TargetReader = std::variant<FrameTarget, ValuesTarget>;

// Largest doubles a reader reads of a target and of a velocity.
long largest_target(const TargetReader& reader);
long largest_velocity(const TargetReader& reader);
// The words of a refusal of a shape.
std::string target_forms(const TargetReader& reader);
std::string velocity_forms(const TargetReader& reader);
// Doubles to read of a target (velocity), or -1: a form the task does not take.
long target_size(const TargetReader& reader, const Floats& f);
long velocity_size(const TargetReader& reader, const Floats& f);

}  // namespace clik
