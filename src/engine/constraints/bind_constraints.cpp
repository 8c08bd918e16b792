// Python entry points of the constraints: ConstraintConfig.from_set, and
// constraint_trace (test-only: runs ConstraintRun.update over a given sequence of
// configurations, for the parity tests against clik/constraints/constraint_run.py).
#include "constraints/bind_constraints.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <nanobind/eigen/dense.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <pinocchio/algorithm/jacobian.hpp>

#include "bindings.hpp"
#include "model_bridge.hpp"

namespace nb = nanobind;
using namespace nb::literals;

namespace clik {

namespace {

// Python values through numpy as a flat list of T, numpy dtype `dtype` (set-up only).
template <typename T>
std::vector<T> numbers(nb::handle h, const char* dtype) {
  nb::module_ np = nb::module_::import_("numpy");
  nb::object flat = np.attr("asarray")(h, "dtype"_a = dtype).attr("ravel")().attr("tolist")();
  std::vector<T> out;
  for (nb::handle x : flat) out.push_back(nb::cast<T>(x));
  return out;
}

std::vector<double> floats(nb::handle h) { return numbers<double>(h, "float64"); }
std::vector<int> ints(nb::handle h) { return numbers<int>(h, "int64"); }

std::vector<std::string> strings(nb::handle h) {
  std::vector<std::string> out;
  for (nb::handle x : h) out.push_back(nb::cast<std::string>(x));
  return out;
}

Vec vec(const std::vector<double>& v) {
  return Eigen::Map<const Vec>(v.data(), static_cast<Eigen::Index>(v.size()));
}

Vec3 vec3(nb::handle h) {
  const std::vector<double> v = floats(h);
  if (v.size() != 3) throw std::invalid_argument("expected 3 numbers");
  return Vec3(v[0], v[1], v[2]);
}

std::optional<double> optional_float(nb::handle h) {
  if (h.is_none()) return std::nullopt;
  return nb::cast<double>(h);
}

// A new numpy array holding a copy of n = prod(shape) values from src.
template <typename T>
nb::object to_numpy(const T* src, std::initializer_list<size_t> shape) {
  size_t n = 1;
  for (size_t s : shape) n *= s;
  T* buf = new T[n > 0 ? n : 1];
  std::copy(src, src + n, buf);
  nb::capsule owner(buf, [](void* p) noexcept { delete[] static_cast<T*>(p); });
  return nb::ndarray<nb::numpy, T>(buf, shape, owner).cast();
}

}  // namespace

ConstraintConfig config_from_set(nb::handle cset) {
  ConstraintConfig cfg;
  nb::object model_obj = cset.attr("robot").attr("model");
  const pinocchio::Model& model = borrow_model(model_obj.ptr());
  cfg.nq = model.nq;
  cfg.nv = model.nv;
  cfg.obstacle_rows = nb::cast<bool>(cset.attr("obstacle_rows"));
  const std::string form = nb::cast<std::string>(cset.attr("form"));
  cfg.form = form == "squared" ? ObstacleForm::squared : ObstacleForm::normalized;
  nb::object gains = cset.attr("gains");
  cfg.obstacle_gain = optional_float(gains["obstacle"]);
  cfg.joint_gain = optional_float(gains["joint"]);
  cfg.self_gain = optional_float(gains["self"]);
  cfg.dexterity_gain = optional_float(gains.attr("get")("dexterity"));  // older dicts lack it
  const std::string release = nb::cast<std::string>(cset.attr("release_rule"));
  cfg.release = release == "sign" ? ReleaseRule::sign : ReleaseRule::projection;
  cfg.hysteresis = nb::cast<double>(cset.attr("hysteresis"));
  nb::object max_active = cset.attr("max_active");
  if (!max_active.is_none()) cfg.max_active = nb::cast<int>(nb::int_(max_active));
  cfg.monitor_margin = nb::cast<double>(cset.attr("monitor_margin"));
  cfg.self_threshold = nb::cast<double>(cset.attr("self_threshold"));

  nb::object scene = cset.attr("scene");
  nb::object obstacles = cset.attr("obstacles");
  const std::vector<double> thr = floats(cset.attr("obs_threshold"));
  const std::vector<double> vel = floats(cset.attr("obs_vel"));
  std::vector<int> geom;
  if (!scene.is_none()) geom = ints(scene.attr("obstacle_geom"));
  int o = 0;
  for (nb::handle ob : obstacles) {
    ObstacleConfig oc;
    oc.name = nb::cast<std::string>(ob.attr("name"));
    const std::vector<double> R = floats(ob.attr("rotation"));
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) oc.rotation(r, c) = R[3 * r + c];
    }
    oc.position = vec3(ob.attr("position"));
    oc.velocity = Vec3(vel[3 * o], vel[3 * o + 1], vel[3 * o + 2]);
    oc.threshold = thr[o];
    oc.geometry = o < static_cast<int>(geom.size()) ? geom[o] : -1;
    cfg.obstacles.push_back(oc);
    ++o;
  }

  nb::object dexterity = cset.attr("dexterity");
  if (!dexterity.is_none()) {
    cfg.dexterity = DexterityConfig{nb::cast<double>(dexterity.attr("threshold"))};
  }

  nb::object jl = cset.attr("joint_limits");
  if (!jl.is_none()) {
    JointLimits j;
    j.n = nb::cast<int>(jl.attr("n"));
    j.q_index = ints(jl.attr("q_index"));
    j.v_index = ints(jl.attr("v_index"));
    j.lower = vec(floats(jl.attr("lower")));
    j.upper = vec(floats(jl.attr("upper")));
    j.threshold = vec(floats(jl.attr("threshold")));
    j.joint_names = strings(jl.attr("joint_names"));
    j.names = strings(jl.attr("names"));
    j.row_threshold = vec(floats(jl.attr("row_threshold")));
    j.sign = vec(floats(jl.attr("sign")));
    cfg.joint_limits = std::move(j);
  }

  if (!scene.is_none()) {
    nb::object gmodel = scene.attr("gmodel");
    SceneConfig sc;
    sc.gmodel = &borrow_geometry_model(gmodel.ptr());
    sc.n_links = nb::cast<int>(scene.attr("n_links"));
    sc.link_joint = ints(scene.attr("link_joint"));
    sc.local_radius = vec(floats(scene.attr("local_radius")));
    const int n_obs = static_cast<int>(cfg.obstacles.size());
    const std::vector<int> pairs = ints(scene.attr("obstacle_pairs"));
    sc.obstacle_pairs.resize(sc.n_links, n_obs);
    for (int i = 0; i < sc.n_links; ++i) {
      for (int k = 0; k < n_obs; ++k) sc.obstacle_pairs(i, k) = pairs[i * n_obs + k];
    }
    for (nb::handle p : scene.attr("self_pairs")) {
      nb::tuple t = nb::borrow<nb::tuple>(p);
      sc.self_pairs.push_back({nb::cast<int>(t[0]), nb::cast<int>(t[1]), nb::cast<int>(t[2])});
    }
    sc.bounding_spheres();
    cfg.link_labels = strings(cset.attr("link_labels"));
    cfg.rho = motion_bounds(model, sc);
    cfg.scene = std::move(sc);
    // Keep the Python GeometryModel (behind the borrowed pointer) alive with the config.
    PyObject* keep = gmodel.release().ptr();
    cfg.owner = std::shared_ptr<void>(keep, [](void* p) {
      nb::gil_scoped_acquire gil;
      Py_DECREF(static_cast<PyObject*>(p));
    });
  }
  return cfg;
}

nb::dict constraint_records(const ConstraintRun& run, int n_rec) {
  const ConstraintConfig& cfg = run.config();
  const int n_obs = cfg.n_obstacles();
  const size_t rows = static_cast<size_t>(n_rec), slots = static_cast<size_t>(run.slots());
  nb::dict out;
  nb::list events;
  for (const Event& e : run.events()) {
    nb::dict d;
    d["t"] = e.t;
    d["constraint"] = run.name(e.key);
    d["action"] = action_name(e.action);
    events.append(d);
  }
  out["events"] = events;
  nb::list names;
  for (int key : run.code_keys()) names.append(run.name(key));
  out["constraint_names"] = names;
  out["active"] = to_numpy(run.rec_active().data(), {rows, slots});
  out["witness"] = to_numpy(run.rec_witness().data(), {rows, slots, 2, 3});
  out["min_obstacle_distance"] = nb::none();
  if (n_obs) {
    out["obstacle_distance"] = to_numpy(run.rec_dist().data(), {rows, size_t(n_obs)});
    out["obstacle_link"] = to_numpy(run.rec_link().data(), {rows, size_t(n_obs)});
    out["min_obstacle_distance"] = run.run_min().minCoeff();
    nb::dict by, link, exact, when;
    for (int o = 0; o < n_obs; ++o) {
      const char* name = cfg.obstacles[o].name.c_str();
      by[name] = run.run_min()[o];
      const int l = run.run_min_link()[o];
      link[name] = l >= 0 ? cfg.link_labels[l] : std::string();
      exact[name] = std::isfinite(run.run_min()[o]);
      when[name] = run.run_min_t()[o];
    }
    out["min_obstacle_distance_by_obstacle"] = by;
    out["min_obstacle_distance_link_by_obstacle"] = link;
    out["min_obstacle_distance_exact_by_obstacle"] = exact;
    out["min_obstacle_distance_time_by_obstacle"] = when;
  }
  nb::list skipped;
  for (const std::string& s : run.skipped_names()) skipped.append(s);
  out["skipped"] = skipped;
  return out;
}

void bind_constraints(nb::module_& m) {
  nb::class_<ConstraintConfig>(m, "ConstraintConfig",
                               "What a run needs from a clik.constraints.ConstraintSet.")
      .def_static("from_set", [](nb::handle cset) { return config_from_set(cset); },
                  nb::arg("cset"), "Read a Python ConstraintSet (its scene's GeometryModel is "
                  "borrowed and kept alive).")
      .def_prop_ro("n_obstacles", &ConstraintConfig::n_obstacles)
      .def_prop_ro("n_links", &ConstraintConfig::n_links)
      .def_prop_ro("n_self", &ConstraintConfig::n_self)
      .def_ro("link_labels", &ConstraintConfig::link_labels)
      .def_prop_ro("rho", [](const ConstraintConfig& c) { return Mat(c.rho); })
      .def(
          "joint_limit_rows",
          [](const ConstraintConfig& c, const Vec& q) {
            if (!c.joint_limits) throw std::invalid_argument("the set has no joint-range rows");
            const JointLimits& jl = *c.joint_limits;
            Vec e(2 * jl.n), excursion(2 * jl.n);
            Mat rows(2 * jl.n, c.nv);
            jl.evaluate(q, e);
            jl.excursion(q, excursion);
            for (int i = 0; i < 2 * jl.n; ++i) jl.row(i, rows.row(i));
            return nb::make_tuple(e, excursion, rows);
          },
          nb::arg("q"), "Test entry: (evaluate(q), excursion(q), every row) of the joint ranges.")
      .def(
          "row_limit",
          [](const ConstraintConfig& c, int m_rows, const std::string& law) {
            return c.row_limit(m_rows, law_kind(law));
          },
          nb::arg("m"), nb::arg("law"));

  m.def(
      "constraint_trace",
      [](nb::handle model_obj, const ConstraintConfig& cfg, int m_rows, const std::string& law,
         double alpha, const Vec& t, int n_rec, double damping, double dt, double beta_max,
         const Vec& K_task, const Mat& Q, const Mat& JT, const Mat& E, const Mat& FF,
         const std::vector<bool>& exact, const std::vector<int>& record_slot, int frame,
         std::vector<int> task_rows) {
        const pinocchio::Model& model = borrow_model(model_obj.ptr());
        const int N = static_cast<int>(Q.rows());
        const int nv = model.nv;
        if (Q.cols() != model.nq || JT.rows() != static_cast<Eigen::Index>(N) * m_rows ||
            JT.cols() != nv || E.rows() != N || FF.rows() != N ||
            static_cast<int>(exact.size()) != N || static_cast<int>(record_slot.size()) != N) {
          throw std::invalid_argument("constraint_trace: inconsistent array shapes");
        }
        const LawKind kind = law_kind(law);
        const TimesView times(t.data(), t.size());
        ConstraintRun run(cfg, model, m_rows, kind, alpha, times, n_rec, frame,
                          std::move(task_rows));
        const int limit = run.limit();
        const int rows = m_rows + std::max(limit, 0);
        LawSettings s;
        s.kind = kind;
        s.damping = damping;
        s.dt = dt;
        s.beta_max = beta_max;
        Law law_(s, rows, nv);
        ExtendedTask ext(m_rows, rows, nv, K_task);
        pinocchio::Data data(model);
        const size_t L = static_cast<size_t>(std::max(limit, 1));
        const int n_obs = cfg.n_obstacles();
        std::vector<std::int32_t> v_out(N, 0);
        std::vector<double> J_out(N * L * nv, 0.0), e_out(N * L, 0.0), K_out(N * L, 0.0),
            ff_out(N * L, 0.0), dmin(N), dist(N * n_obs), manip(N);
        std::vector<std::int32_t> link(N * n_obs);
        std::vector<std::uint8_t> exact_out(N * n_obs);
        nb::list active_names, penetrations;
        for (int k = 0; k < N; ++k) {
          const Vec q = Q.row(k).transpose();
          pinocchio::computeJointJacobians(model, data, q);
          ext.J.topRows(m_rows) = JT.middleRows(static_cast<Eigen::Index>(k) * m_rows, m_rows);
          ext.e.head(m_rows) = E.row(k).transpose();
          ext.ff.head(m_rows) = FF.row(k).transpose();
          const int v = run.update(k, q, data, ext, law_, exact[k]);
          v_out[k] = v;
          for (int s_ = 0; s_ < v; ++s_) {
            const size_t at = static_cast<size_t>(k) * L + s_;
            for (int c = 0; c < nv; ++c) J_out[at * nv + c] = ext.J(m_rows + s_, c);
            e_out[at] = ext.e[m_rows + s_];
            K_out[at] = ext.K[m_rows + s_];
            ff_out[at] = ext.ff[m_rows + s_];
          }
          dmin[k] = run.min_distance;
          manip[k] = run.manipulability;
          for (int o = 0; o < n_obs; ++o) {
            dist[k * n_obs + o] = run.dist_o[o];
            link[k * n_obs + o] = run.link_o[o];
            exact_out[k * n_obs + o] = run.exact_o[o];
          }
          nb::list names;
          for (const Candidate& c : run.active()) names.append(run.name(c.key));
          active_names.append(names);
          nb::list pen;
          for (const auto& [key, d] : run.self_penetrations) pen.append(nb::make_tuple(run.name(key), d));
          penetrations.append(pen);
          if (record_slot[k] >= 0) run.record(record_slot[k]);
        }
        nb::dict out;
        const size_t n = static_cast<size_t>(N), no = static_cast<size_t>(n_obs);
        out["v"] = to_numpy(v_out.data(), {n});
        out["J"] = to_numpy(J_out.data(), {n, L, static_cast<size_t>(nv)});
        out["e"] = to_numpy(e_out.data(), {n, L});
        out["K"] = to_numpy(K_out.data(), {n, L});
        out["ff"] = to_numpy(ff_out.data(), {n, L});
        out["min_distance"] = to_numpy(dmin.data(), {n});
        out["manipulability"] = to_numpy(manip.data(), {n});
        out["dist_o"] = to_numpy(dist.data(), {n, no});
        out["link_o"] = to_numpy(link.data(), {n, no});
        out["exact_o"] = to_numpy(exact_out.data(), {n, no});
        out["active_names"] = active_names;
        out["self_penetrations"] = penetrations;
        out["limit"] = limit;
        out["records"] = constraint_records(run, n_rec);
        return out;
      },
      nb::arg("model"), nb::arg("config"), nb::arg("m"), nb::arg("law"), nb::arg("alpha"),
      nb::arg("t"), nb::arg("n_rec"), nb::arg("damping"), nb::arg("dt"), nb::arg("beta_max"),
      nb::arg("K_task"), nb::arg("Q"), nb::arg("JT"), nb::arg("E"), nb::arg("FF"),
      nb::arg("exact"), nb::arg("record_slot"), nb::arg("frame") = -1,
      nb::arg("task_rows") = std::vector<int>{},
      "Test driver: ConstraintRun.update at each configuration Q[k] (task rows JT[k*m:(k+1)*m], "
      "E[k], FF[k]; recorded in slot record_slot[k] >= 0; frame and task_rows: the task's, for "
      "the dexterity row); per-sample rows, distances and manipulability, and the run's "
      "records.");
}

}  // namespace clik
