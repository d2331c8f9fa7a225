// The compiled half of the Python module `penumbra` (python/penumbra/):
// conversions between NumPy arrays, Python strings and the C++ libraries,
// nothing else. Every check and every number comes from the code the
// command line runs: the scene reader (read_scene), the method table and
// shade() (the evaluator's per-sample factor), render_with, run_cli.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <tbb/global_control.h>

#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "cli/cli.h"
#include "cli/command.h"
#include "core/shading.h"
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

// The evaluator's factor at each sample: shade() on a white Lambertian base,
// Ng = Ni (analytic shapes), as `penumbra contour` evaluates it; NaN where
// an adjustment's or model's effective factor is undefined.
py::array_t<double> factor(const std::string& terminator_json, const Directions& ng,
                           const Directions& ns, const Directions& wi, const Directions& wo,
                           const Directions& visibility) {
  const TerminatorSettings t =
      terminator_from_json(parse_json_text(terminator_json, "pn.factor"), "pn.factor");
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
    Material white;
    white.albedo = 1.0;
    for (py::ssize_t k = 0; k < n; ++k) {
      ShadingPoint p;
      static_cast<AdjustVectors&>(p) = {g[k], g[k], s[k], i[k], o[k]};
      p.visibility = v[k];
      const Shaded shaded = shade(t, white, p, nullptr);
      f[k] = shaded.factor_defined ? shaded.factor : std::numeric_limits<double>::quiet_NaN();
    }
  }
  return out;
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

}  // namespace
}  // namespace penumbra

PYBIND11_MODULE(_penumbra, m) {
  using namespace penumbra;
  m.doc() = "Penumbra's C++ libraries; use the package `penumbra`, not this module.";
  py::register_exception_translator(translate_input_error);
  m.def("methods_json", [] { return methods_json().dump(); });
  m.def("factor", &factor);
  m.def("load_scene", &scene_document);
  m.def("render", &render_arrays);
  m.def("read_exr", &read_arrays);
  m.def("write_exr", &write_arrays);
  m.def("cli", &cli);
}
