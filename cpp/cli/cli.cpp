#include "cli/cli.h"

#include <algorithm>
#include <memory>
#include <optional>
#include <thread>

#include <fmt/format.h>
#include <tbb/global_control.h>
#include <CLI/CLI.hpp>

#include "cli/commands.h"
#include "export/export.h"
#include "image/image_io.h"
#include "scene/scene_json.h"
#include "util/data_files.h"
#include "util/strict_json.h"

namespace penumbra {

namespace {

void add_scene_options(CLI::App* cmd, SceneArgs& a) {
  cmd->add_option("--method", a.method, "terminator method id (see `penumbra methods`)");
  cmd->add_option("--offset", a.offset,
                  "shadow-ray origin method of a low-poly mesh (see `penumbra methods`)");
  cmd->add_option("--segments", a.segments,
                  "tessellate the shape: segments around the axis "
                  "(sets /shape/tessellation/segments)")
      ->check(CLI::Range(3, 65536));
  cmd->add_option("--representation", a.representation, "smooth, bump or displacement");
  cmd->add_option("--width", a.width, "image width in pixels")->check(CLI::PositiveNumber);
  cmd->add_option("--height", a.height, "image height in pixels")->check(CLI::PositiveNumber);
  cmd->add_option("--spp", a.spp, "samples per pixel")->check(CLI::PositiveNumber);
  cmd->add_option("--set", a.sets, "override a scene value: /json/pointer=VALUE (repeatable)");
}

// The external renderers' ids, for `export --to`.
std::vector<std::string> external_renderer_ids() {
  std::vector<std::string> ids;
  for (const RendererInfo& info : renderer_table())
    if (info.kind != RendererKind::kEvaluator) ids.push_back(info.id);
  return ids;
}

}  // namespace

namespace {

// "penumbra rendr": name the unknown subcommand and list the real ones
// (CLI11 only says the argument was not expected).
std::optional<std::string> unknown_subcommand(CLI::App& app, int argc, const char* const* argv) {
  if (argc < 2 || argv[1][0] == '-') return std::nullopt;
  std::string names;
  for (const CLI::App* sub : app.get_subcommands({})) {
    if (sub->get_name() == argv[1]) return std::nullopt;
    names += (names.empty() ? "" : ", ") + sub->get_name();
  }
  return fmt::format("unknown subcommand \"{}\" (expected one of: {})", printable(argv[1], 60),
                     names);
}

// The height map and its pyramid: shared by `pyramid` and `filtering`.
void add_map_options(CLI::App* cmd, PyramidArgs& a) {
  cmd->add_option("heights", a.heights, "height map (EXR, PNG, ...)")->required();
  cmd->add_option("-o,--output", a.output, "output folder")->required();
  cmd->add_option("--channel", a.channel,
                  "the height channel (required when the file has several)");
  cmd->add_option("--texel-size", a.texel_size,
                  "scene units per texel (default: 1 / width, the map spans one unit)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--height-scale", a.height_scale, "scene units per unit of the file's values")
      ->capture_default_str();
  cmd->add_option("--edge", a.edge, "differences across the map's edge: wrap (tiled) or clamp")
      ->capture_default_str();
}

// `pyramid`, `bake` and `filtering`: the bump-map filtering commands.
CLI::App* add_pyramid_command(CLI::App& app, PyramidArgs& pyramid_args) {
  CLI::App* pyramid_cmd =
      app.add_subcommand("pyramid",
                         "a height map's bump (offset) and roughness pyramids, one EXR per level "
                         "(Schilling; see README)");
  add_map_options(pyramid_cmd, pyramid_args);
  pyramid_cmd->add_flag("-q,--quiet", pyramid_args.quiet, "print nothing on success");
  return pyramid_cmd;
}

CLI::App* add_bake_command(CLI::App& app, BakeArgs& bake_args) {
  CLI::App* bake_cmd = app.add_subcommand(
      "bake",
      "a scene's analytic height function (/height) as a height map of the plane z = 0, or as a "
      "height or normal map over its shape's (u, v)");
  bake_cmd->add_option("scene", bake_args.scene, "scene file (JSON)")->required();
  bake_cmd->add_option("-o,--output", bake_args.output, "height map (.exr)")->required();
  bake_cmd->add_option("--set", bake_args.sets, "JSON-pointer override, /pointer=VALUE");
  bake_cmd->add_option("--size", bake_args.size, "texels a side")
      ->check(CLI::Range(1, 16384))
      ->capture_default_str();
  bake_cmd->add_option("--extent", bake_args.extent, "side of the baked square, scene units")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  bake_cmd
      ->add_option("--on", bake_args.on,
                   "plane: the plane z = 0 (for penumbra pyramid and filtering); shape: the "
                   "scene's cylinder or sphere over its map parameters (u, v), --size texels "
                   "around and as many along v as keep texels square")
      ->check(CLI::IsMember({"plane", "shape"}))
      ->capture_default_str();
  bake_cmd
      ->add_option("--kind", bake_args.kind,
                   "height: amplitude * h in scene units (channel Y); normal: the exact bump "
                   "normal as a tangent-space normal map (R, G, B = 0.5 n + 0.5; --on shape only)")
      ->check(CLI::IsMember({"height", "normal"}))
      ->capture_default_str();
  return bake_cmd;
}

CLI::App* add_filtering_command(CLI::App& app, FilteringArgs& filtering_args) {
  CLI::App* filtering_cmd = app.add_subcommand(
      "filtering",
      "the bump-filtering experiment (RTG Fig. 12-6) on a height map: each roughness "
      "filter against the unfiltered footprint, 1 to 64 texels per pixel");
  add_map_options(filtering_cmd, filtering_args.map);
  filtering_cmd->add_option("--alpha", filtering_args.alphas,
                            "base GGX alpha (repeatable; default 0.01 0.05 0.1 0.2 0.4 0.8)");
  filtering_cmd->add_option("--filter", filtering_args.filters,
                            "roughness filter id (repeatable; default: every measurable one)");
  filtering_cmd
      ->add_option("--max-level", filtering_args.max_level,
                   "coarsest level measured (2^level texels per pixel side)")
      ->check(CLI::Range(0, 16))
      ->capture_default_str();
  filtering_cmd->add_option("--footprints", filtering_args.footprints, "footprints per level")
      ->check(CLI::Range(2, 100000))
      ->capture_default_str();
  filtering_cmd->add_option("--view", filtering_args.view_deg, "view zenith angle, degrees")
      ->check(CLI::Range(0.0, 80.0))
      ->capture_default_str();
  filtering_cmd
      ->add_option("--sweep-step", filtering_args.sweep_step_deg, "light sweep step, degrees")
      ->check(CLI::Range(0.05, 10.0))
      ->capture_default_str();
  filtering_cmd
      ->add_option("--shift", filtering_args.shift,
                   "pixel grid offset from the texel grid, pixels, [0, 1) (0: aligned), or "
                   "random (each footprint its own, from the seed)")
      ->capture_default_str();
  filtering_cmd
      ->add_option("--lookup", filtering_args.lookup,
                   "what the filters read: box (the footprint's exact moments) or trilinear "
                   "(the pyramid's mip-map lookup)")
      ->check(CLI::IsMember({"box", "trilinear"}))
      ->capture_default_str();
  filtering_cmd->add_option("--jobs", filtering_args.jobs, "threads (default: all cores)")
      ->check(CLI::NonNegativeNumber);
  filtering_cmd->add_flag("-q,--quiet", filtering_args.map.quiet, "print nothing on success");
  return filtering_cmd;
}

}  // namespace

int run_cli(int argc, const char* const* argv, std::ostream& out, std::ostream& err) {
  CLI::App app{"Penumbra: shadow-terminator laboratory (reference evaluator)", "penumbra"};
  app.require_subcommand(1);
  app.set_version_flag("--version", kPenumbraVersion);
  const std::string exit_status = exit_status_text();
  app.footer(exit_status);
  // Global options (--threads) are accepted after the subcommand too.
  app.fallthrough();
  int threads = 0;
  app.add_option("--threads", threads, "worker threads (default: all cores)")
      ->check(CLI::Range(1, 1024));

  bool methods_json = false;
  CLI::App* methods = app.add_subcommand("methods", "list the terminator methods");
  methods->add_flag("--json", methods_json, "print a JSON array");

  bool renderers_json = false;
  CLI::App* renderers = app.add_subcommand(
      "renderers", "list the renderers: package, version probe, methods and offsets offered");
  renderers->add_flag("--json", renderers_json, "print a JSON array");

  RenderArgs r;
  CLI::App* render_cmd = app.add_subcommand(
      "render", "render a scene with the evaluator, POV-Ray or Blender Cycles (--renderer)");
  render_cmd->add_option("scene", r.scene, "scene JSON file")->required();
  render_cmd->add_option("-o,--output", r.output, "output OpenEXR file")->required();
  render_cmd->add_option("--preview", r.preview, "also write an sRGB PNG preview");
  add_scene_options(render_cmd, r.scene_args);
  render_cmd->add_flag("-q,--quiet", r.quiet, "no progress or summary");

  render_cmd->add_option("--renderer", r.renderer,
                         "renderer id: " + renderer_choices() +
                             " (default evaluator; see "
                             "`penumbra renderers`)");
  render_cmd->add_option("--timeout", r.timeout, "seconds an external renderer may run")
      ->check(CLI::PositiveNumber);
  render_cmd
      ->add_option("--max-memory", r.max_memory_gib,
                   "refuse a render estimated to need more memory (GiB)")
      ->check(CLI::Range(0.001, 1e6))
      ->capture_default_str();

  ExportArgs x;
  CLI::App* export_cmd =
      app.add_subcommand("export", "write a scene for POV-Ray (.pov) or Blender (job + mesh)");
  export_cmd->add_option("--to", x.to, "povray or blender")
      ->required()
      ->check(CLI::IsMember(external_renderer_ids()));
  export_cmd->add_option("scene", x.scene, "scene JSON file")->required();
  export_cmd->add_option("-o,--output", x.output, "output folder")->required();
  add_scene_options(export_cmd, x.scene_args);

  CompareArgs c;
  CLI::App* compare_cmd = app.add_subcommand(
      "compare", "terminator-profile and image metrics of TEST against REFERENCE");
  compare_cmd
      ->add_option("reference", c.reference,
                   "reference image (a Penumbra EXR, e.g. displacement, or another renderer's)")
      ->required();
  compare_cmd->add_option("test", c.test, "image to compare (EXR, PNG, TIFF, ...)")->required();
  compare_cmd->add_flag("--json", c.json, "print JSON");
  compare_cmd->add_option("-o,--output", c.difference,
                          "write the difference image (test - reference, R G B; A the smaller "
                          "coverage) as OpenEXR");
  compare_cmd
      ->add_option("--scale", c.scale,
                   "albedo*E/pi in W m^-2 sr^-1 (default: from the penumbra:scene metadata of the "
                   "reference, else of the test)")
      ->check(CLI::PositiveNumber);
  compare_cmd
      ->add_option("--max-profile-rmse", c.max_rmse,
                   "exit 3 when the overall profile RMSE exceeds this")
      ->check(CLI::NonNegativeNumber);
  compare_cmd->add_option(
      "--mask", c.mask,
      "coverage of an image without an A channel: an image of the same size "
      "(its A channel, else its first; 1 object, 0 background); before --threshold");
  compare_cmd
      ->add_option("--threshold", c.threshold,
                   "coverage of an image without an A channel: its lit region, radiance >= "
                   "FRACTION * albedo*E/pi; alone: 0.05, the profile's dark level (write "
                   "--threshold=F before the images)")
      ->expected(0, 1)
      ->default_str("0.05")
      ->type_name("FRACTION")
      ->check(CLI::Range(0.0, 1e6));
  compare_cmd->add_flag("--no-mask", c.no_mask,
                        "image metrics over every pixel, with the usual (unmasked) SSIM");
  compare_cmd->add_flag("--same-scene", c.same_scene,
                        "exit 2 when the images' penumbra:scene show different geometry, camera "
                        "or light (default: a warning)");

  CalibrationOptions cal;
  cal.scenes_dir = data_file("scenes/calibration");
  cal.output_dir = "results/calibration";
  cal.jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  bool cal_quiet = false;
  CLI::App* calibrate_cmd = app.add_subcommand(
      "calibrate", "render the calibration set with all three renderers and compare them");
  calibrate_cmd->add_option("-o,--output", cal.output_dir, "output folder")->capture_default_str();
  calibrate_cmd->add_option("--scenes", cal.scenes_dir, "folder with cylinder.json and sphere.json")
      ->capture_default_str();
  calibrate_cmd->add_option("--jobs", cal.jobs, "renders in parallel (default: cores)")
      ->check(CLI::Range(1, 256));
  calibrate_cmd->add_option("--timeout", cal.timeout_s, "seconds per external render")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  calibrate_cmd->add_option("--blender-spp", cal.blender_spp, "Cycles samples per pixel")
      ->check(CLI::Range(1, 65536))
      ->capture_default_str();
  calibrate_cmd->add_option("--set", cal.sets, "override a value of both base scenes");
  calibrate_cmd->add_flag("-q,--quiet", cal_quiet, "no per-render lines");

  RunArgs run_args;
  CLI::App* run_cmd = app.add_subcommand(
      "run", "run a study: renders (cached, resumable), metrics, report.json/csv/html, figures");
  run_cmd->add_option("study", run_args.study, "study JSON file")->required();
  run_cmd->add_option("-o,--output", run_args.output, "output folder (default results/NAME)");
  run_cmd->add_option("--jobs", run_args.jobs, "renders in parallel (default: cores)")
      ->check(CLI::Range(1, 256));
  run_cmd->add_option("--timeout", run_args.timeout, "seconds per external render")
      ->check(CLI::PositiveNumber);
  run_cmd
      ->add_option("--max-renders", run_args.max_renders,
                   "start at most this many new renders, then stop (resume later)")
      ->check(CLI::NonNegativeNumber);
  run_cmd->add_flag("--no-figures", run_args.no_figures, "skip matplotlib figures and report.html");
  run_cmd->add_flag("--self-contained", run_args.self_contained,
                    "report.html embeds every image (one file to mail; default: it links "
                    "images/ and figures/ beside it)");
  run_cmd->add_flag("--dry-run", run_args.dry_run,
                    "validate and count the renders (and cache hits); write nothing");
  run_cmd
      ->add_option("--max-memory", run_args.max_memory_gib,
                   "refuse a study with a render estimated to need more memory (GiB, per render)")
      ->check(CLI::Range(0.001, 1e6))
      ->capture_default_str();
  run_cmd->add_flag("-q,--quiet", run_args.quiet, "no progress");
  run_cmd
      ->add_option("--executor", run_args.executor,
                   "local: render here, --jobs at a time; slurm: submit the missing renders as "
                   "a Slurm job array and a report job that depends on it, then return")
      ->check(CLI::IsMember({"local", "slurm"}))
      ->capture_default_str();
  run_cmd->add_option("--partition", run_args.slurm.partition,
                      "slurm: partition of the array and report jobs (default: the cluster's)");
  run_cmd
      ->add_option("--array-limit", run_args.slurm.array_limit,
                   "slurm: array tasks running at once")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  run_cmd
      ->add_option("--renders-per-task", run_args.slurm.renders_per_task,
                   "slurm: renders per array task, at most (a variant's ground-truth "
                   "convergence chain takes a task of its own; renders that share a mesh "
                   "share a task where they fit)")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  run_cmd->add_option("--sbatch-arg", run_args.slurm.sbatch_args,
                      "slurm: an argument for every sbatch call, as it is "
                      "(--sbatch-arg=--time=2:00:00; repeatable)");
  run_cmd
      ->add_option("--slurm-chain", run_args.slurm.chain,
                   "internal: the report job's chain of submissions")
      ->group("");

  RunBatchArgs batch_args;
  CLI::App* batch_cmd = app.add_subcommand(
      "run-batch",
      "render one array task of a Slurm study's batch file into its cache (run by sbatch)");
  batch_cmd->add_option("batch", batch_args.batch, "batch file (STUDY_DIR/slurm/batch-*.json)")
      ->required();
  batch_cmd->add_option("--task", batch_args.task, "task index (default: SLURM_ARRAY_TASK_ID)")
      ->check(CLI::NonNegativeNumber);

  std::string status_folder;
  CLI::App* status_cmd =
      app.add_subcommand("status", "progress of a study folder's Slurm submissions");
  status_cmd->add_option("folder", status_folder, "study output folder")->required();

  std::string report_folder;
  CLI::App* report_cmd = app.add_subcommand(
      "report", "redraw the figures and report.html of a study folder from its report.json");
  report_cmd->add_option("folder", report_folder, "study output folder (holds report.json)")
      ->required();
  bool report_self_contained = false;
  report_cmd->add_flag("--self-contained", report_self_contained,
                       "report.html embeds every image (one file to mail; default: it links "
                       "images/ and figures/ beside it)");

  std::vector<std::string> contour_methods;
  std::string contour_output = "results/contour";
  double contour_step = 1.0;
  CLI::App* contour_cmd = app.add_subcommand(
      "contour", "contour plots of G over light angle x normal deviation (Chiang Fig. 5)");
  contour_cmd->add_option("--method", contour_methods, "method id (repeatable, in plot order)")
      ->required();
  contour_cmd->add_option("-o,--output", contour_output, "output folder")->capture_default_str();
  contour_cmd->add_option("--step", contour_step, "grid step in degrees")
      ->check(CLI::Range(0.05, 10.0))
      ->capture_default_str();

  int bench_size = 512, bench_spp = 16;
  CLI::App* bench = app.add_subcommand("bench", "print evaluator throughput figures");
  bench->add_option("--size", bench_size, "image size in pixels")->check(CLI::Range(16, 4096));
  bench->add_option("--spp", bench_spp, "samples per pixel")->check(CLI::Range(1, 1024));
  int bench_povray_rounds = 0;
  bench
      ->add_option("--povray", bench_povray_rounds,
                   "instead of the table: the evaluator against POV-Ray on the same scene, CPU "
                   "seconds per render, this many paired rounds (needs POV-Ray)")
      ->check(CLI::Range(1, 100));

  PyramidArgs pyramid_args;
  CLI::App* pyramid_cmd = add_pyramid_command(app, pyramid_args);
  BakeArgs bake_args;
  CLI::App* bake_cmd = add_bake_command(app, bake_args);
  FilteringArgs filtering_args;
  CLI::App* filtering_cmd = add_filtering_command(app, filtering_args);

  bool exit_codes_json = false;
  CLI::App* exit_codes = app.add_subcommand(
      "exit-codes", "list the exit statuses of every command (code, name, meaning)");
  exit_codes->add_flag("--json", exit_codes_json,
                       "print a JSON array of {code, name, meaning} (the signal row: code 128, "
                       "meaning \"128+N: ...\")");

  for (CLI::App* sub : app.get_subcommands({})) sub->footer(exit_status);
  if (const auto unknown = unknown_subcommand(app, argc, argv)) {
    err << "penumbra: error: " << *unknown << " (see penumbra --help)\n";
    return kExitBadInput;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e, out, err);  // --help, --version
    err << "penumbra: error: " << e.what() << " (see penumbra --help)\n";
    return kExitBadInput;
  }

  std::unique_ptr<tbb::global_control> limit;
  if (threads > 0)
    limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                  threads);
  try {
    if (*methods) return command_methods(methods_json, out);
    if (*renderers) return command_renderers(renderers_json, out);
    if (*report_cmd) return command_report(report_folder, report_self_contained, out, err);
    if (*render_cmd) return command_render(r, out, err);
    if (*export_cmd) return command_export(x, out);
    if (*compare_cmd) return command_compare(c, out, err);
    if (*calibrate_cmd) return command_calibrate(cal, cal_quiet, out, err);
    if (*run_cmd) return command_run(run_args, out, err);
    if (*batch_cmd) return command_run_batch(batch_args, out, err);
    if (*status_cmd) return command_status(status_folder, out);
    if (*contour_cmd) return command_contour(contour_methods, contour_step, contour_output, out);
    if (*bench) return command_bench(bench_size, bench_spp, bench_povray_rounds, out);
    if (*pyramid_cmd) return command_pyramid(pyramid_args, out);
    if (*filtering_cmd) return command_filtering(filtering_args, out, err);
    if (*bake_cmd) return command_bake(bake_args, out);
    if (*exit_codes) return command_exit_codes(exit_codes_json, out);
  } catch (const InputError& e) {
    err << "penumbra: error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const ExportError& e) {
    err << "penumbra: error: cannot export: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const UsageError& e) {
    err << "penumbra: error: " << e.what() << " (see penumbra --help)\n";
    return kExitBadInput;
  } catch (const OutputError& e) {
    err << "penumbra: error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const RenderCancelled& e) {
    err << "penumbra: stopped: " << e.what() << "; nothing written\n";
    return StopSignals::exit_code();
  } catch (const RendererError& e) {
    err << "penumbra: failed: " << e.what() << "\n";
    return kExitFailure;
  } catch (const std::exception& e) {
    err << "penumbra: failed: " << e.what() << "\n";
    return kExitFailure;
  }
  return kExitBadInput;
}

}  // namespace penumbra
