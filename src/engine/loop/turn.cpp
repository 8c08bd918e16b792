// One controller, one thread at a time: see turn.hpp.
#include "loop/turn.hpp"

#include <nanobind/stl/string.h>

namespace nb = nanobind;

namespace clik {

bool Turn::claim() {
  bool free = false;
  return busy_.compare_exchange_strong(free, true, std::memory_order_acquire,
                                       std::memory_order_relaxed);
}

void Turn::take(const char* who) {
  const unsigned long me = PyThread_get_thread_ident();
  if (claim()) {  // free: taken at once (with the GIL held: no other Python thread runs)
    owner_.store(me, std::memory_order_relaxed);
    return;
  }
  if (owner_.load(std::memory_order_relaxed) == me) refuse(who);  // a re-entry
  nb::gil_scoped_release release;  // the thread that has the turn may need the GIL
  std::unique_lock<std::mutex> lock(mutex_);
  ++waiting_;
  free_.wait(lock, [this] { return claim(); });
  --waiting_;
  owner_.store(me, std::memory_order_relaxed);
}

void Turn::give() {
  owner_.store(0, std::memory_order_relaxed);  // no thread mistakes the turn for its own
  busy_.store(false);  // seq_cst: ordered before the load below (a waiter's ++ then check)
  if (waiting_.load() > 0) {
    { std::lock_guard<std::mutex> lock(mutex_); }  // a waiter checks, then sleeps, under it
    free_.notify_all();
  }
}

bool Turn::mine() const {
  return busy_.load() && owner_.load() == PyThread_get_thread_ident();
}

void Turn::refuse(const char* who) const {
  nb::object error = refuse_(
      nb::str(who),
      "one thread at a time: a controller's step, reset, result and move_obstacle wait for "
      "each other across threads, but cannot run inside one another in the same thread",
      "a call made while this thread was inside the controller (from a target's __array__, a "
      "garbage-collection or weakref callback, or a signal handler)");
  PyErr_SetObject(reinterpret_cast<PyObject*>(Py_TYPE(error.ptr())), error.ptr());
  throw nb::python_error();
}

void bind_turn(nb::module_& m) {
  nb::class_<Turn>(m, "Turn",
                   "One controller, one thread at a time: its step, reset, result and "
                   "move_obstacle each hold it (with turn: ...); other threads wait, the same "
                   "thread is refused.")
      .def(nb::init<nb::object>(), nb::arg("refuse"),
           "refuse(field, expected, got): the error raised on a re-entry (clik.InputError).")
      .def(
          "take", [](Turn& t, const std::string& who) { t.take(who.c_str()); }, nb::arg("who"),
          "Takes the turn for `who` (a method's name, in the refusal): waits while another "
          "thread has it; refused when this thread has it.")
      .def("give", &Turn::give, "Gives the turn back.")
      .def("mine", &Turn::mine, "Whether the calling thread holds the turn.");
}

}  // namespace clik
