// One controller, one thread at a time (`_engine.Turn`; docs/guides/online-control.md,
// "Threads"): a controller's step, reset, result and move_obstacle each take its turn.
// Called from several threads, they wait for each other (the waiting thread releases the
// GIL); called again from inside one of them in the same thread (a target's __array__, a
// garbage-collection callback, a weakref callback run in the middle of a tick), the inner
// call is refused: it raises the error the turn was given (clik.InputError), naming the
// rule. The Python engine's ticks take the same turn (clik/control/ticks.py).
#pragma once

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <string>

#include <Python.h>
#include <nanobind/nanobind.h>

namespace clik {

class Turn {
 public:
  // refuse(field, expected, got): the error raised on a re-entry (clik.InputError).
  explicit Turn(nanobind::object refuse) : refuse_(std::move(refuse)) {}

  // Takes the turn for `who` (e.g. "Controller.step"): at once when free; after the
  // thread that has it gives it back (the GIL released meanwhile); refused (a Python
  // error raised) when this thread has it already.
  void take(const char* who);
  void give();
  // Whether this thread has the turn (a step inside a Python-held turn: obstacles moved).
  bool mine() const;

  // The turn held for a scope.
  class Held {
   public:
    Held(Turn& turn, const char* who) : turn_(turn) { turn_.take(who); }
    ~Held() { turn_.give(); }
    Held(const Held&) = delete;
    Held& operator=(const Held&) = delete;

   private:
    Turn& turn_;
  };

 private:
  [[noreturn]] void refuse(const char* who) const;

  bool claim();  // whether this call took a free turn

  nanobind::object refuse_;
  std::atomic<bool> busy_{false};
  std::atomic<unsigned long> owner_{0};  // PyThread_get_thread_ident() of the holder, or 0
  std::atomic<int> waiting_{0};          // threads waiting for the turn
  std::mutex mutex_;                     // for the waiting threads (with free_)
  std::condition_variable free_;
};

void bind_turn(nanobind::module_& m);  // `_engine.Turn`

}  // namespace clik
