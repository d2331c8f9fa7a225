// The Blender driver: exports the scene, renders it with harness/blender_render.py
// in a Blender process of its own or a serving one (BlenderSessions). In
// Blender's part of the cache key (code_digest.h), not the evaluator's.
#include <stdlib.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <thread>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "renderers/external/blender/blender.h"
#include "renderers/external/blender/blender_sessions.h"
#include "renderers/external/external.h"
#include "util/data_files.h"
#include "util/files.h"
#include "util/process.h"
#include "util/strict_json.h"

namespace penumbra {
namespace fs = std::filesystem;
using namespace external;

std::string blender_script(const RenderSettings& s) {
  std::string script = s.blender_script;
  if (script.empty() && std::getenv("PENUMBRA_BLENDER_SCRIPT"))
    script = std::getenv("PENUMBRA_BLENDER_SCRIPT");
  if (script.empty()) script = data_file("harness/blender_render.py");
  if (!fs::is_regular_file(script))
    throw RendererError(fmt::format("blender: the harness script {} is missing", script));
  return fs::absolute(script).string();
}

namespace {

// Blender processes are ended and replaced after this many jobs, which
// bounds what Blender may leak across resets.
constexpr int kMaxJobsPerSession = 64;

// Blender runs on one thread (-t 1, which covers Cycles too): on more, it
// sums a mesh's vertex normals in an order that varies from run to run, and
// a displaced surface's render then differs by an ulp in a pixel or two
// (blender_render.py, single_threaded). A study renders several jobs at
// once instead.
std::vector<std::string> blender_argv(const std::string& exe, const std::string& script,
                                      const std::vector<std::string>& script_args) {
  std::vector<std::string> argv{
      exe, "-b",       "-t",   "1", "--factory-startup", "-noaudio", "--python-exit-code",
      "1", "--python", script, "--"};
  argv.insert(argv.end(), script_args.begin(), script_args.end());
  return argv;
}

// Penumbra's environment with the folder of Blender's executable first in
// PATH. Blender's embedded Python finds its standard library from the first
// `python3` on PATH: a pyenv, conda or virtualenv one first would give it a
// library without numpy (or of another version), and every render would fail.
std::vector<std::string> blender_environment(const std::string& exe) {
  std::vector<std::string> env;
  std::string path = "PATH=" + fs::path(exe).parent_path().string();
  for (char** e = environ; e && *e; ++e) {
    const std::string entry = *e;
    if (entry.rfind("PATH=", 0) == 0)
      path += ":" + entry.substr(5);
    else
      env.push_back(entry);
  }
  env.push_back(path);
  return env;
}

// The bytes appended to `path` since `offset`.
std::string read_from(const std::string& path, std::uintmax_t offset) {
  std::ifstream in(path, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(offset));
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

std::uintmax_t file_size_or_zero(const std::string& path) {
  std::error_code ec;
  const std::uintmax_t n = fs::file_size(path, ec);
  return ec ? 0 : n;
}

}  // namespace

struct BlenderSessions::Session {
  std::thread::id owner;
  std::string executable, script, log_path, cwd;
  std::unique_ptr<Coprocess> process;
  int served = 0, starts = 0;
};

BlenderSessions::BlenderSessions(std::string folder) : folder_(std::move(folder)) {}

BlenderSessions::~BlenderSessions() {
  for (auto& s : idle_)
    if (s->process) s->process->close(5.0);
  idle_.clear();
  std::error_code ec;
  if (!work_.empty()) fs::remove_all(work_, ec);
}

std::unique_ptr<BlenderSessions::Session> BlenderSessions::acquire(const std::string& executable,
                                                                   const std::string& script) {
  std::lock_guard<std::mutex> lock(mutex_);
  // A process ends with the thread that started it (Coprocess), so a thread
  // only ever uses the processes it started itself.
  const std::thread::id self = std::this_thread::get_id();
  std::erase_if(
      idle_, [](const std::unique_ptr<Session>& s) { return !s->process || !s->process->alive(); });
  for (auto it = idle_.begin(); it != idle_.end(); ++it)
    if ((*it)->owner == self && (*it)->executable == executable && (*it)->script == script) {
      std::unique_ptr<Session> s = std::move(*it);
      idle_.erase(it);
      return s;
    }
  if (work_.empty()) {
    std::string pattern =
        (fs::path(folder_) / work_folder_pattern(blender_entry().info.id)).string();
    if (!::mkdtemp(pattern.data()))
      throw RendererError(fmt::format("cannot create a work folder in {}", folder_));
    work_ = fs::absolute(pattern).string();
  }
  auto s = std::make_unique<Session>();
  s->owner = self;
  s->executable = executable, s->script = script, s->cwd = work_;
  s->log_path = (fs::path(work_) / fmt::format("blender-{}.log", next_id_++)).string();
  return s;
}

void BlenderSessions::release(std::unique_ptr<Session> session) {
  std::lock_guard<std::mutex> lock(mutex_);
  started_ += std::exchange(session->starts, 0);
  if (session->process && session->process->alive()) idle_.push_back(std::move(session));
}

int BlenderSessions::started() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return started_;
}

namespace {

// The failure of a served job: the process ended (crash, timeout, stopped)
// or answered with an .error file.
[[noreturn]] void blender_job_failed(const std::optional<ProcessResult>& ended,
                                     const std::string& answer, const RenderSettings& settings,
                                     WorkDir& work, const std::string& rerun) {
  if (ended && ended->cancelled) {
    work.keep = false;
    throw RenderCancelled("blender was stopped (interrupted)");
  }
  std::string what = "failed: " + printable(answer, 400);
  if (ended && ended->timed_out)
    what = fmt::format("timed out after {:.0f} s (the limit; raise it with --timeout)",
                       settings.timeout_s);
  else if (ended && ended->signal != 0)
    what = fmt::format("was killed by signal {}", ended->signal);
  else if (ended)
    what = fmt::format("exited with status {} before the render was done", ended->exit_code);
  throw RendererError(fmt::format(
      "blender {}; log {} (work files kept in {}; rerun by hand: {}), "
      "last lines:\n{}",
      what, settings.log_path, work.path.string(), rerun, tail_lines(settings.log_path, 12)));
}

// Renders the job in `work` with a serving Blender process (started if it
// is not running); its log lines for this job are copied to the job's log.
// Returns the wall time of the job.
double serve_blender_job(BlenderSessions::Session& s, WorkDir& work,
                         const RenderSettings& settings) {
  if (s.process && (!s.process->alive() || s.served >= kMaxJobsPerSession)) {
    s.process->close(5.0);
    s.process.reset();
  }
  if (!s.process) {
    s.process = std::make_unique<Coprocess>(blender_argv(s.executable, s.script, {"--serve"}),
                                            s.cwd, s.log_path, blender_environment(s.executable));
    s.served = 0, ++s.starts;
  }
  ++s.served;
  const fs::path output = work.path / "render.exr";
  const std::string error_path = output.string() + ".error";
  const std::uintmax_t log_offset = file_size_or_zero(s.log_path);
  nlohmann::json request{{"job", (work.path / kBlenderJobFile).string()},
                         {"output", output.string()},
                         {"threads", 1}};  // blender_argv's -t 1 holds anyway
  const auto t0 = std::chrono::steady_clock::now();
  s.process->send_line(request.dump());  // a process gone shows in the wait
  const std::optional<ProcessResult> ended = s.process->wait_until(
      [&] { return fs::exists(output) || fs::exists(error_path); }, settings.timeout_s);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (s.log_path != settings.log_path) {
    const std::string lines = read_from(s.log_path, log_offset);
    std::ofstream(settings.log_path, std::ios::binary | std::ios::app) << lines;
  }
  if (ended || !fs::exists(output)) {
    std::ifstream in(error_path);
    std::string answer;
    std::getline(in, answer);
    std::string rerun = fmt::format(
        "cd {} && {}", work.path.string(),
        fmt::join(blender_argv(s.executable, s.script, {kBlenderJobFile, "render.exr"}), " "));
    blender_job_failed(ended, answer, settings, work, rerun);
  }
  return seconds;
}

// Hands the session back to the pool whatever happens.
struct SessionLease {
  BlenderSessions* pool;
  std::unique_ptr<BlenderSessions::Session> session;
  ~SessionLease() {
    if (pool)
      pool->release(std::move(session));
    else if (session && session->process)
      session->process->close(5.0);
  }
};

}  // namespace

RendererRun render_blender(const Scene& scene, const RenderSettings& settings) {
  const RendererInfo& info = blender_entry().info;
  const BlenderExport job = export_blender(scene);
  const std::string exe = executable_for(info, settings);
  const std::string script = blender_script(settings);
  WorkDir work(settings.log_path, info);
  try {
    write_blender_files(job, work.path.string());
  } catch (const std::exception& e) {  // the work folder, not the user's output
    throw RendererError(fmt::format("cannot write the Blender job: {}", e.what()));
  }
  SessionLease lease{settings.blender_sessions, nullptr};
  if (lease.pool) {
    lease.session = lease.pool->acquire(exe, script);
  } else {  // a process of its own, logging straight into the job's log
    lease.session = std::make_unique<BlenderSessions::Session>();
    lease.session->executable = exe, lease.session->script = script;
    lease.session->cwd = work.path.string(), lease.session->log_path = settings.log_path;
  }
  const double seconds = serve_blender_job(*lease.session, work, settings);
  const Image colour = read_renderer_image(info, (work.path / "render.exr").string());
  return with_geometry(info, colour, seconds, scene, settings, work);
}

}  // namespace penumbra
