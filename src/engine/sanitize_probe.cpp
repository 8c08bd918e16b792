// clik._sanitize_probe: undefined behaviour and a bad read on request, so that
// `make sanitize` can check first that a report fails its run and shows in its log
// (tests/robustness/test_sanitizer_probe.py). Built only with -DCLIK_SANITIZE_PROBE=ON,
// which only the sanitizer build passes (CMakeLists.txt): never in a normal build.
#include <nanobind/nanobind.h>

#include <climits>
#include <memory>

namespace nb = nanobind;

namespace {

// UBSan: signed integer overflow (INT_MAX + 1 for `by` = 1).
int signed_overflow(int by) {
  volatile int top = INT_MAX;
  return top + by;
}

// ASan: heap-buffer-overflow, reading element `index` of a 4-int heap array (4: one past).
int heap_overflow_read(int index) {
  auto values = std::make_unique<int[]>(4);
  volatile int* data = values.get();
  return data[index];
}

}  // namespace

NB_MODULE(_sanitize_probe, m) {
  m.doc() = "make sanitize's planted reports (sanitizer builds only)";
  m.def("signed_overflow", &signed_overflow, nb::arg("by") = 1,
        "INT_MAX + by in C++ int: UBSan's 'signed integer overflow' for by > 0.");
  m.def("heap_overflow_read", &heap_overflow_read, nb::arg("index") = 4,
        "Reads element `index` of a 4-int heap array: ASan's heap-buffer-overflow for 4.");
}
