// The compiled half of the Python module `penumbra` (python/penumbra/):
// conversions between NumPy arrays, Python strings and the C++ libraries,
// nothing else. Every check and every number comes from the code the
// command line runs: the scene reader (read_scene), the method table and
// shade() (the evaluator's per-sample factor), render_with, run_cli.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <tbb/global_control.h>

#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "cli/cli.h"
#include "cli/command.h"
#include "core/shading.h"
#include "core/shadow_origin.h"
#include "core/user_method.h"
#include "image/exr_file.h"
#include "image/image_io.h"
#include "renderers/renderers.h"
#include "util/strict_json.h"

namespace py = pybind11;

namespace penumbra {
namespace {

using Directions = py::array_t<double, py::array::c_style | py::array::forcecast>;
using Floats = py::array_t<float, py::array::c_style | py::array::forcecast>;

// penumbra.SceneError (python/penumbra/_errors.py), raised for InputError.
py::object& scene_error_class() {
  static py::object cls = py::module_::import("penumbra._errors").attr("SceneError");
  return cls;
}

void translate_input_error(std::exception_ptr p) {
  try {
    if (p) std::rethrow_exception(p);
  } catch (const InputError& e) {
    const py::object error = scene_error_class()(e.what(), e.file(), e.pointer(), e.reason());
    PyErr_SetObject(scene_error_class().ptr(), error.ptr());
  }
}

const Vec3* rows_of(const Directions& a, py::ssize_t n, const char* name) {
  if (a.ndim() != 2 || a.shape(1) != 3 || a.shape(0) != n)
    throw py::value_error(std::string(name) +
                          ": expected an (N, 3) array with N = " + std::to_string(n));
  static_assert(sizeof(Vec3) == 3 * sizeof(double));
  return reinterpret_cast<const Vec3*>(a.data());
}

// The evaluator's factor at each sample: shade() on the material (a white
// Lambertian base where `material_json` is empty), Ng = Ni (analytic
// shapes), as `penumbra contour` evaluates it; NaN where an adjustment's or
// model's effective factor is undefined.
py::array_t<double> factor(const std::string& terminator_json, const Directions& ng,
                           const Directions& ns, const Directions& wi, const Directions& wo,
                           const Directions& visibility, const std::string& material_json) {
  const TerminatorSettings t =
      terminator_from_json(parse_json_text(terminator_json, "pn.factor"), "pn.factor");
  Material material;
  material.albedo = 1.0;
  if (!material_json.empty())
    material = material_from_json(parse_json_text(material_json, "pn.factor"), "pn.factor");
  const py::ssize_t n = ng.ndim() == 2 ? ng.shape(0) : -1;
  const Vec3* g = rows_of(ng, n, "ng");
  const Vec3* s = rows_of(ns, n, "ns");
  const Vec3* i = rows_of(wi, n, "wi");
  const Vec3* o = rows_of(wo, n, "wo");
  if (visibility.ndim() != 1 || visibility.shape(0) != n)
    throw py::value_error("visibility: expected an (N,) array");
  const double* v = visibility.data();
  py::array_t<double> out(n);
  double* f = out.mutable_data();
  {
    py::gil_scoped_release release;
    for (py::ssize_t k = 0; k < n; ++k) {
      ShadingPoint p;
      static_cast<AdjustVectors&>(p) = {g[k], g[k], s[k], i[k], o[k]};
      p.visibility = v[k];
      const Shaded shaded = shade(t, material, p, nullptr);
      f[k] = shaded.factor_defined ? shaded.factor : std::numeric_limits<double>::quiet_NaN();
    }
  }
  return out;
}

// A read-only NumPy view of `data` (no copy): valid while the batch is,
// which is the call's duration.
// An empty span may have no address; NumPy wants one all the same.
const void* address(const void* data) {
  static const double none = 0.0;
  return data ? data : &none;
}

py::array_t<double> view(std::span<const double> data) {
  const auto* at = static_cast<const double*>(address(data.data()));
  py::array_t<double> a({py::ssize_t(data.size())}, {py::ssize_t(sizeof(double))}, at,
                        py::capsule(at, [](void*) {}));
  a.attr("setflags")(py::arg("write") = false);
  return a;
}
py::array_t<double> view(std::span<const Vec3> data) {
  py::array_t<double> a({py::ssize_t(data.size()), py::ssize_t(3)},
                        {py::ssize_t(sizeof(Vec3)), py::ssize_t(sizeof(double))},
                        static_cast<const double*>(address(data.data())),
                        py::capsule(address(data.data()), [](void*) {}));
  a.attr("setflags")(py::arg("write") = false);
  return a;
}

// The text of the Python exception being handled: "ValueError: message".
std::string python_error(const py::error_already_set& e) {
  const std::string type = py::str(e.type().attr("__name__"));
  const std::string value = py::str(e.value());
  return value.empty() ? type : type + ": " + value;
}

// Calls a user's function on a batch: with the GIL, the cosines as views,
// its parameters (and the vectors, when it asked for them) as keywords.
void call_user_function(const py::object& function, const UserMethod& m, const FactorBatch& b,
                        std::span<const double> values, std::span<double> g) {
  py::gil_scoped_acquire gil;
  try {
    py::dict keywords;
    for (std::size_t k = 0; k < m.parameters.size(); ++k)
      keywords[py::str(m.parameters[k].name)] = values[k];
    if (m.wants_vectors) {
      keywords["ng"] = view(b.ng), keywords["ns"] = view(b.ns);
      keywords["wi"] = view(b.wi), keywords["wo"] = view(b.wo);
    }
    const py::object result = function(view(b.cos_light), view(b.cos_deviation),
                                       view(b.cos_shading), view(b.cos_view), **keywords);
    using Result = py::array_t<double, py::array::c_style | py::array::forcecast>;
    const Result a = Result::ensure(result);
    if (!a) PyErr_Clear();
    if (!a || a.ndim() != 1 || a.shape(0) != py::ssize_t(g.size())) {
      std::string shape = "a " + std::string(py::str(result.get_type().attr("__name__")));
      if (a) {
        shape = "an array of shape (";
        for (py::ssize_t d = 0; d < a.ndim(); ++d)
          shape += (d ? ", " : "") + std::to_string(a.shape(d));
        shape += a.ndim() == 1 ? ",)" : ")";
      }
      throw UserMethodError("user method \"" + m.id + "\" (" + m.source + ") returned " + shape +
                            " for a batch of " + std::to_string(g.size()) +
                            " samples: expected an array of shape (" + std::to_string(g.size()) +
                            ",)");
    }
    std::copy_n(a.data(), g.size(), g.data());
  } catch (py::error_already_set& e) {
    throw UserMethodError("user method \"" + m.id + "\" (" + m.source + ") raised " +
                          python_error(e));
  }
}

// penumbra.method: registers `function` under `id` (core/user_method.h).
// parameters: (name, default, min, max, description) each.
void register_method(
    const std::string& id, const py::function& function, const std::string& source,
    const std::string& digest,
    const std::vector<std::tuple<std::string, double, double, double, std::string>>& parameters,
    double min_value, double max_value, bool wants_vectors) {
  auto m = std::make_shared<UserMethod>();
  m->id = id;
  m->source = source;
  m->digest = digest;
  for (const auto& [name, value, lo, hi, description] : parameters)
    m->parameters.push_back({name, value, lo, hi, description});
  m->min_value = min_value;
  m->max_value = max_value;
  m->wants_vectors = wants_vectors;
  // Never destroyed: the registry outlives the interpreter, and a Python
  // object must not be released after it is gone.
  const auto* held = new py::object(function);
  const UserMethod* self = m.get();
  m->factor = [held, self](const FactorBatch& b, std::span<const double> values,
                           std::span<double> g) { call_user_function(*held, *self, b, values, g); };
  try {
    register_user_method(std::move(m));
  } catch (const std::invalid_argument& e) {
    throw py::value_error(e.what());
  }
}

// A user method's G at each sample, through the same checks as a render
// (evaluate_user_method), on the cosines of the given vectors; `terminator`
// gives its parameters (and Ng or Ni, which is the same vector here).
py::array_t<double> user_factor(const std::string& terminator_json, const Directions& ng,
                                const Directions& ns, const Directions& wi, const Directions& wo) {
  const TerminatorSettings t =
      terminator_from_json(parse_json_text(terminator_json, "pn.factor"), "pn.factor");
  if (!t.method.user) throw py::value_error("pn.factor: not a user method");
  const py::ssize_t n = ng.ndim() == 2 ? ng.shape(0) : -1;
  const std::span<const Vec3> g_(rows_of(ng, n, "ng"), std::size_t(n));
  const std::span<const Vec3> s_(rows_of(ns, n, "ns"), std::size_t(n));
  const std::span<const Vec3> i_(rows_of(wi, n, "wi"), std::size_t(n));
  const std::span<const Vec3> o_(rows_of(wo, n, "wo"), std::size_t(n));
  const auto count = std::size_t(n);
  std::vector<double> cos_light(count), cos_deviation(count), cos_shading(count), cos_view(count);
  for (std::size_t k = 0; k < std::size_t(n); ++k) {
    cos_light[k] = dot(g_[k], i_[k]);
    cos_deviation[k] = dot(g_[k], s_[k]);
    cos_shading[k] = dot(s_[k], i_[k]);
    cos_view[k] = dot(g_[k], o_[k]);
  }
  const bool vectors = t.method.user->wants_vectors;
  FactorBatch batch{cos_light, cos_deviation, cos_shading, cos_view, {}, {}, {}, {}};
  if (vectors) batch.ng = g_, batch.ns = s_, batch.wi = i_, batch.wo = o_;
  py::array_t<double> out(n);
  std::span<double> f(out.mutable_data(), std::size_t(n));
  {
    py::gil_scoped_release release;
    evaluate_user_method(*t.method.user, batch, t.method.user_values, f);
  }
  return out;
}

std::vector<std::string> user_methods() {
  return user_method_ids();
}

// The low-poly section's shadow-ray origin (core/shadow_origin.h) at N hits
// on flat triangles: `vertices` and `normals` (N, 3, 3), `barycentrics`
// (N, 3) the weights of the vertices, ng the triangle's normal on the
// shaded side, ns the shading normal, wi towards the light. Returns the
// (N, 3) origins and whether each ray skips its own triangle.
py::tuple offset(const std::string& offset_json, const Directions& vertices,
                 const Directions& normals, const Directions& barycentrics, const Directions& ng,
                 const Directions& ns, const Directions& wi, bool backfacing) {
  const OffsetSettings settings =
      offset_from_json(parse_json_text(offset_json, "pn.offset"), "pn.offset");
  const py::ssize_t n = ng.ndim() == 2 ? ng.shape(0) : -1;
  auto triangles = [n](const Directions& a, const char* name) {
    if (a.ndim() != 3 || a.shape(0) != n || a.shape(1) != 3 || a.shape(2) != 3)
      throw py::value_error(std::string(name) +
                            ": expected an (N, 3, 3) array with N = " + std::to_string(n));
    return reinterpret_cast<const Vec3*>(a.data());
  };
  const Vec3* v = triangles(vertices, "vertices");
  const Vec3* m = triangles(normals, "normals");
  const Vec3* b = rows_of(barycentrics, n, "barycentrics");
  const Vec3* g = rows_of(ng, n, "ng");
  const Vec3* s = rows_of(ns, n, "ns");
  const Vec3* i = rows_of(wi, n, "wi");
  py::array_t<double> origins({n, py::ssize_t(3)});
  py::array_t<bool> skip(n);
  auto* o = reinterpret_cast<Vec3*>(origins.mutable_data());
  bool* self = skip.mutable_data();
  {
    py::gil_scoped_release release;
    for (py::ssize_t k = 0; k < n; ++k) {
      ShadowQuery q;
      for (int c = 0; c < 3; ++c) {
        q.triangle.v[c] = v[3 * k + c];
        q.triangle.n[c] = m[3 * k + c];
      }
      q.triangle.b[0] = b[k].x, q.triangle.b[1] = b[k].y, q.triangle.b[2] = b[k].z;
      q.p = b[k].x * q.triangle.v[0] + b[k].y * q.triangle.v[1] + b[k].z * q.triangle.v[2];
      q.ng = g[k], q.ns = s[k], q.wi = i[k];
      q.backfacing = backfacing;
      const ShadowOrigin r = shadow_ray_origin(settings, q);
      o[k] = r.origin;
      self[k] = r.skip_self;
    }
  }
  return py::make_tuple(origins, skip);
}

LoadedScene load(const std::string& path, const std::string& document_json, const py::dict& o);

// `penumbra export` of a scene file or document: what the exporter prints.
std::string export_files(const std::string& path, const std::string& document_json,
                         const py::dict& options, const std::string& to,
                         const std::string& output) {
  const std::optional<RendererKind> r = renderer_from_id(to);
  if (!r) throw py::value_error("to: expected povray or blender, got \"" + to + "\"");
  const LoadedScene loaded = load(path, document_json, options);
  py::gil_scoped_release release;
  return export_scene_files(*r, loaded.scene, output);
}

SceneArgs scene_args(const py::dict& o) {
  SceneArgs a;
  if (o.contains("method")) a.method = o["method"].cast<std::string>();
  if (o.contains("representation")) a.representation = o["representation"].cast<std::string>();
  if (o.contains("width")) a.width = o["width"].cast<int>();
  if (o.contains("height")) a.height = o["height"].cast<int>();
  if (o.contains("spp")) a.spp = o["spp"].cast<int>();
  if (o.contains("sets")) a.sets = o["sets"].cast<std::vector<std::string>>();
  return a;
}

// A scene file, or a document (JSON text) read from `path`, as the CLI reads it.
LoadedScene load(const std::string& path, const std::string& document_json, const py::dict& o) {
  if (document_json.empty()) return read_scene(path, scene_args(o));
  return read_scene_document(parse_json_text(document_json, path), path, scene_args(o));
}

std::string scene_document(const std::string& path, const std::string& document_json,
                           const py::dict& options) {
  return load(path, document_json, options).document.dump();
}

// An image as one (height, width, channels) float32 array over its own
// pixels (no copy), with its channel names.
py::tuple image_to_python(Image image) {
  auto owner = std::make_unique<Image>(std::move(image));
  const Image& im = *owner;
  const auto c = py::ssize_t(im.channels.size());
  const py::capsule free(owner.get(), [](void* p) { delete static_cast<Image*>(p); });
  py::array_t<float> pixels({py::ssize_t(im.height), py::ssize_t(im.width), c}, im.pixels.data(),
                            free);
  owner.release();
  return py::make_tuple(im.channels, pixels);
}

// `penumbra render` without the file: (channels, pixels, attributes).
py::tuple render_arrays(const std::string& path, const std::string& document_json,
                        const py::dict& options, const std::string& renderer_id, int threads) {
  const std::optional<RendererKind> renderer = renderer_from_id(renderer_id);
  if (!renderer)
    throw py::value_error("renderer: expected " + renderer_choices("") + ", got \"" + renderer_id +
                          "\"");
  const LoadedScene loaded = load(path, document_json, options);
  check_offered(*renderer, loaded.scene);
  RenderSettings settings;
  settings.threads = threads;  // external renderers
  RendererRun run;
  {
    py::gil_scoped_release release;
    // The evaluator's limit, as the command line's --threads sets it (cli.cpp).
    std::unique_ptr<tbb::global_control> limit;
    if (threads > 0)
      limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                    std::size_t(threads));
    run = render_with(*renderer, loaded.scene, settings);
  }
  const py::tuple image = image_to_python(std::move(run.image));
  return py::make_tuple(image[0], image[1], render_attributes(loaded, *renderer));
}

py::tuple read_arrays(const std::string& path) {
  std::map<std::string, std::string> attributes;
  Image image = read_exr_file(path, &attributes);
  const py::tuple t = image_to_python(std::move(image));
  return py::make_tuple(t[0], t[1], attributes);
}

void write_arrays(const std::vector<std::string>& channels, const Floats& pixels,
                  const std::string& path,
                  const std::vector<std::pair<std::string, std::string>>& attributes) {
  if (pixels.ndim() != 3 || pixels.shape(2) != py::ssize_t(channels.size()))
    throw py::value_error("pixels: expected a (height, width, channels) array");
  Image image;
  image.height = int(pixels.shape(0));
  image.width = int(pixels.shape(1));
  image.channels = channels;
  image.pixels.assign(pixels.data(), pixels.data() + pixels.size());
  write_exr(image, path, attributes);
}

// The command line in this process: (exit status, stdout, stderr).
py::tuple cli(const std::vector<std::string>& args) {
  std::vector<const char*> argv{"penumbra"};
  for (const std::string& a : args) argv.push_back(a.c_str());
  std::ostringstream out, err;
  int status = 0;
  {
    py::gil_scoped_release release;
    status = run_cli(int(argv.size()), argv.data(), out, err);
  }
  return py::make_tuple(status, out.str(), err.str());
}

// The command line in this process, writing to the process's own standard
// streams as it goes (progress included): its exit status.
int cli_console(const std::vector<std::string>& args) {
  std::vector<const char*> argv{"penumbra"};
  for (const std::string& a : args) argv.push_back(a.c_str());
  py::gil_scoped_release release;
  const int status = run_cli(int(argv.size()), argv.data(), std::cout, std::cerr);
  std::cout.flush();
  return status;
}

}  // namespace
}  // namespace penumbra

PYBIND11_MODULE(_penumbra, m) {
  using namespace penumbra;
  m.doc() = "Penumbra's C++ libraries; use the package `penumbra`, not this module.";
  py::register_exception_translator(translate_input_error);
  py::register_exception<UserMethodError>(m, "UserMethodError", PyExc_RuntimeError);
  m.def("methods_json", [] { return methods_json().dump(); });
  m.def("factor", &factor);
  m.def("load_scene", &scene_document);
  m.def("render", &render_arrays);
  m.def("read_exr", &read_arrays);
  m.def("write_exr", &write_arrays);
  m.def("cli", &cli);
  m.def("cli_console", &cli_console);
  m.def("register_method", &register_method);
  m.def("user_factor", &user_factor);
  m.def("user_methods", &user_methods);
  m.def("offset", &offset);
  m.def("export", &export_files);
}
