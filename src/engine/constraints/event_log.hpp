// A run's constraint events (mirrors clik/constraints/event_log.py): every one kept (an
// offline run, whose events are bounded by its samples), or the last `capacity` (a
// controller's session, which has no last sample: bounded like its record), with a count
// of those dropped. Events are numbered from 0 in the order they happened; the i-th is
// kept while total() - i <= kept(). Nothing is allocated once a bounded log is full.
#pragma once

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <vector>

namespace clik {

enum class EventAction : std::uint8_t { activate, release, skipped };
const char* action_name(EventAction action);  // constraints/constraint_run.cpp

struct Event {
  double t;  // [s], rounded to 9 decimals as round(t, 9) in Python
  int key;
  EventAction action;
};

class EventLog {
 public:
  // capacity: the events kept, >= 1; 0: every one.
  explicit EventLog(long capacity = 0) : capacity_(capacity) {
    if (capacity < 0) throw std::invalid_argument("EventLog: capacity >= 0 (0: every event)");
    events_.reserve(static_cast<std::size_t>(capacity > 0 ? std::min(capacity, 256L) : 256L));
  }

  void push(const Event& e) {
    if (capacity_ == 0 || total_ < capacity_) {
      events_.push_back(e);
    } else {
      events_[static_cast<std::size_t>(total_ % capacity_)] = e;
    }
    ++total_;
  }

  long total() const { return total_; }  // every event so far
  long kept() const { return static_cast<long>(events_.size()); }
  long dropped() const { return total_ - kept(); }
  // The i-th event of the run, dropped() <= i < total() (a copy: the log may grow).
  Event at(long i) const {
    if (i < dropped() || i >= total_) throw std::out_of_range("EventLog: an event not kept");
    const long slot = capacity_ == 0 ? i : i % capacity_;
    return events_[static_cast<std::size_t>(slot)];
  }

 private:
  long capacity_;
  long total_ = 0;
  std::vector<Event> events_;  // a ring once full (bounded): event i at slot i % capacity
};

}  // namespace clik
