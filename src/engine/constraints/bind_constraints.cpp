// Python entry points of the constraints: the typed configs (the scene, the set, each
// kind's through its own bind()), the constants the engines share, and the records.
#include "constraints/bind_constraints.hpp"

#include <algorithm>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <nanobind/eigen/dense.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/variant.h>
#include <nanobind/stl/vector.h>

#include "bindings.hpp"
#include "constraints/constraint_set.hpp"
#include "constraints/kinds.hpp"
#include "model/model_bridge.hpp"

namespace nb = nanobind;

namespace clik {

namespace {

// A new numpy array holding a copy of n = prod(shape) values from src.
template <typename T>
nb::object to_numpy(const T* src, const std::vector<std::size_t>& shape) {
  std::size_t n = 1;
  for (std::size_t s : shape) n *= s;
  T* buf = new T[n > 0 ? n : 1];
  std::copy(src, src + n, buf);
  nb::capsule owner(buf, [](void* p) noexcept { delete[] static_cast<T*>(p); });
  return nb::ndarray<nb::numpy, T>(buf, shape.size(), shape.data(), owner).cast();
}

// A kind's record as Python sees it; a per-sample array cut to the n_rec kept.
nb::object exported(const RecordArray& a, int n_rec) {
  std::vector<std::size_t> shape = a.shape;
  if (a.per_sample && !shape.empty()) shape[0] = std::min(shape[0], std::size_t(n_rec));
  using T = RecordArray::Type;
  if (a.as_list) {
    nb::list out;
    const auto* v = static_cast<const std::int32_t*>(a.data);
    for (std::size_t i = 0; i < (shape.empty() ? 0 : shape[0]); ++i) out.append(v[i]);
    return out;
  }
  switch (a.type) {
    case T::i16:
      return to_numpy(static_cast<const std::int16_t*>(a.data), shape);
    case T::i32:
      return to_numpy(static_cast<const std::int32_t*>(a.data), shape);
    case T::f64:
      break;
  }
  return to_numpy(static_cast<const double*>(a.data), shape);
}

// The Python object a borrowed model's owner holds.
nb::object held(const std::shared_ptr<void>& owner) {
  return nb::borrow<nb::object>(static_cast<PyObject*>(owner.get()));
}

ReleaseRule release_rule(const std::string& release) {
  if (release == "projection") return ReleaseRule::projection;
  if (release == "sign") return ReleaseRule::sign;
  throw std::invalid_argument("ConstraintSetConfig: release 'projection' or 'sign', got '" +
                              release + "'");
}

void bind_scene(nb::module_& m) {
  using Pair = std::tuple<int, int, int>;
  nb::class_<SceneConfig>(m, "SceneConfig",
                          "The collision scene's link geometry and pairs (CollisionScene).")
      .def(
          "__init__",
          [](SceneConfig* self, nb::handle gmodel, int n_links, std::vector<int> link_joint,
             const Vec& local_radius, const Eigen::MatrixXi& obstacle_pairs,
             const std::vector<Pair>& self_pairs, std::vector<std::string> link_labels) {
            SceneConfig sc;
            sc.gmodel = &borrow_geometry_model(gmodel.ptr());
            sc.owner = hold(gmodel.ptr());
            sc.n_links = n_links;
            sc.link_joint = std::move(link_joint);
            sc.local_radius = local_radius;
            sc.obstacle_pairs = obstacle_pairs;
            for (const auto& [pair, a, b] : self_pairs) sc.self_pairs.push_back({pair, a, b});
            sc.link_labels = std::move(link_labels);
            sc.prepare();
            new (self) SceneConfig(std::move(sc));
          },
          nb::kw_only(), nb::arg("gmodel"), nb::arg("n_links"), nb::arg("link_joint"),
          nb::arg("local_radius"), nb::arg("obstacle_pairs"), nb::arg("self_pairs"),
          nb::arg("link_labels"),
          "gmodel: the scene's pin.GeometryModel (borrowed, kept alive); obstacle_pairs "
          "(n_links, n_obs) collision pair indices; self_pairs [(pair, a, b)].")
      .def_prop_ro("gmodel", [](const SceneConfig& s) { return held(s.owner); })
      .def_ro("n_links", &SceneConfig::n_links)
      .def_ro("link_joint", &SceneConfig::link_joint)
      .def_ro("local_radius", &SceneConfig::local_radius)
      .def_ro("obstacle_pairs", &SceneConfig::obstacle_pairs)
      .def_prop_ro("self_pairs",
                   [](const SceneConfig& s) {
                     std::vector<Pair> out;
                     for (const auto& p : s.self_pairs) out.emplace_back(p.pair, p.a, p.b);
                     return out;
                   })
      .def_ro("link_labels", &SceneConfig::link_labels);
}

void bind_set(nb::module_& m) {
  nb::class_<ConstraintSetConfig>(m, "ConstraintSetConfig",
                                  "What a run needs from a clik.constraints.ConstraintSet.")
      .def(
          "__init__",
          [](ConstraintSetConfig* self, nb::handle model, std::vector<KindConfig> kinds,
             std::optional<SceneConfig> scene, const std::string& release, double hysteresis,
             std::optional<int> max_active, double monitor_margin) {
            ConstraintSetConfig c;
            c.model = &borrow_model(model.ptr());
            c.owner = hold(model.ptr());
            c.kinds = std::move(kinds);
            c.scene = std::move(scene);
            c.release = release_rule(release);
            c.hysteresis = hysteresis;
            c.max_active = max_active;
            c.monitor_margin = monitor_margin;
            c.built = ModelShape::of(*c.model);
            c.validate();
            new (self) ConstraintSetConfig(std::move(c));
          },
          nb::kw_only(), nb::arg("model"), nb::arg("kinds"), nb::arg("scene").none(),
          nb::arg("release"), nb::arg("hysteresis"), nb::arg("max_active").none(),
          nb::arg("monitor_margin"),
          "model: the robot's pin.Model (borrowed, kept alive); kinds: the kinds' configs in "
          "the set's order; scene: a SceneConfig or None; release 'projection' or 'sign'.")
      .def_prop_ro("model", [](const ConstraintSetConfig& c) { return held(c.owner); })
      .def_ro("kinds", &ConstraintSetConfig::kinds)
      .def_ro("scene", &ConstraintSetConfig::scene)
      .def_prop_ro("release",
                   [](const ConstraintSetConfig& c) {
                     return c.release == ReleaseRule::sign ? "sign" : "projection";
                   })
      .def_ro("hysteresis", &ConstraintSetConfig::hysteresis)
      .def_ro("max_active", &ConstraintSetConfig::max_active)
      .def_ro("monitor_margin", &ConstraintSetConfig::monitor_margin)
      .def_prop_ro("rho",
                   [](const ConstraintSetConfig& c) -> std::optional<Mat> {
                     if (!c.scene) return std::nullopt;
                     c.require_unchanged();
                     return motion_bounds(*c.model, *c.scene);
                   },
                   "Motion bounds (n_links, nv) of the scene's link geometry "
                   "(CollisionScene.motion_bounds), or None without a scene.")
      .def(
          "row_limit",
          [](const ConstraintSetConfig& c, int m_rows, const std::string& law) {
            c.require_unchanged();
            require(m_rows >= 1, "row_limit: m, at least 1 task row");
            return c.row_limit(m_rows, law_kind(law));
          },
          nb::arg("m"), nb::arg("law"), "The bound on active rows (ConstraintSet.row_limit).");
}

}  // namespace

nb::dict constraint_records(const ConstraintRun& run, int n_rec) {
  const auto rows = static_cast<std::size_t>(n_rec), slots = static_cast<std::size_t>(run.slots());
  nb::dict out;
  nb::list events;
  const EventLog& log = run.events();
  for (long i = log.dropped(); i < log.total(); ++i) {
    const Event e = log.at(i);  // a copy: nothing of the run is held across Python calls
    nb::dict d;
    d["t"] = e.t;
    d["constraint"] = run.name(e.key);
    d["action"] = action_name(e.action);
    events.append(d);
  }
  out["events"] = events;
  out["events_dropped"] = log.dropped();
  nb::list names;
  for (int key : run.code_keys()) names.append(run.name(key));
  out["constraint_names"] = names;
  out["active"] = to_numpy(run.rec_active().data(), {rows, slots});
  out["witness"] = to_numpy(run.rec_witness().data(), {rows, slots, 2, 3});
  nb::list active;
  for (const std::string& name : run.active_names()) active.append(name);
  out["active_names"] = active;
  nb::list skipped;
  for (const std::string& s : run.skipped_names()) skipped.append(s);
  out["skipped"] = skipped;
  out["limit"] = run.limit();
  nb::list kinds;
  for (int slot = 0; slot < run.n_kinds(); ++slot) {
    nb::dict records;
    for (const RecordArray& a : run.kind_records(slot)) {
      records[a.name.c_str()] = exported(a, n_rec);
    }
    kinds.append(records);
  }
  out["kinds"] = kinds;
  return out;
}

void bind_constraints(nb::module_& m) {
  m.attr("AT_THRESHOLD") = AT_THRESHOLD;
  m.attr("GJK_TOLERANCE") = GJK_TOLERANCE;
  m.attr("CONTACT_DISTANCE") = CONTACT_DISTANCE;
  m.attr("MIN_WITNESS_GAP") = MIN_WITNESS_GAP;
  m.attr("PARALLEL_SINE") = PARALLEL_SINE;
  m.attr("SINGULAR_DAMPING") = SINGULAR_DAMPING;
  bind_scene(m);
  for_each_kind_config([&](auto* kind) { std::remove_pointer_t<decltype(kind)>::bind(m); });
  bind_set(m);
}

}  // namespace clik
