#include "study/slurm.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "image/image_io.h"
#include "scene/scene_json.h"
#include "study/execute.h"
#include "util/data_files.h"
#include "util/files.h"
#include "util/process.h"
#include "util/strict_json.h"

namespace penumbra {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr const char* kBatchFormat = "penumbra-slurm-batch";

fs::path slurm_folder(const std::string& study_folder) {
  return fs::path(study_folder) / "slurm";
}

std::string failure_path(const RenderCache& cache, const std::string& key) {
  return (fs::path(cache.folder()) / (key + ".failed")).string();
}

std::string read_failure(const RenderCache& cache, const std::string& key) {
  return read_file(failure_path(cache, key));
}

// ---- batch files -------------------------------------------------------------------------

json job_to_json(const Job& job) {
  return {{"key", job.key},         {"label", job.label},     {"renderer", to_string(job.renderer)},
          {"method", job.method},   {"origin", job.origin},   {"truth", job.truth},
          {"variant", job.variant}, {"scene", job.scene_json}};
}

// The batch files of `folder`'s slurm/, parsed, oldest first (names sort by time).
std::vector<std::pair<std::string, json>> read_batches(const std::string& study_folder) {
  std::vector<std::pair<std::string, json>> out;
  std::error_code ec;
  for (fs::directory_iterator it(slurm_folder(study_folder), ec), end; !ec && it != end;
       it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind("batch-", 0) != 0 || it->path().extension() != ".json") continue;
    try {
      out.emplace_back(it->path().string(), read_json_file(it->path().string()));
    } catch (const InputError&) {  // half-written by a killed submitter: not a batch
    }
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  return out;
}

std::string new_chain() {
  const auto now = std::chrono::system_clock::now().time_since_epoch();
  return fmt::format("{}-{}-{}", std::chrono::duration_cast<std::chrono::seconds>(now).count(),
                     host_tag(), ::getpid());
}

// ---- sbatch and squeue -------------------------------------------------------------------

// Runs a Slurm client command; returns its output (stdout and stderr).
std::string run_slurm_command(const std::vector<std::string>& argv, const SlurmOptions& options,
                              const fs::path& logs) {
  const std::optional<std::string> exe = find_executable(argv[0]);
  if (!exe)
    throw RendererError(fmt::format(
        "slurm: `{}` not found (install the Debian package slurm-client: apt-get install "
        "slurm-client; the cluster must be reachable from here)",
        argv[0]));
  std::vector<std::string> full = argv;
  full[0] = *exe;
  const std::string log = (logs / fmt::format(".{}-{}.out", argv[0], ::getpid())).string();
  std::error_code ec;
  fs::remove(log, ec);
  const ProcessResult p = run_process(full, logs.string(), log, options.timeout_s);
  const std::string text = read_file(log);
  fs::remove(log, ec);
  if (!p.ok())
    throw RendererError(fmt::format("slurm: `{}` {}: {}", argv[0],
                                    p.timed_out ? "timed out" : "failed", printable(text, 400)));
  return text;
}

// The job id `sbatch --parsable` printed ("123" or "123;cluster").
std::string parse_job_id(const std::string& output) {
  static const std::regex id(R"((^|\n)([0-9]+)(;[^\n]*)?\s*$)");
  std::smatch m;
  if (!std::regex_search(output, m, id))
    throw RendererError("slurm: sbatch printed no job id: " + printable(output, 300));
  return m[2].str();
}

std::vector<std::string> sbatch_common(const SlurmOptions& options) {
  std::vector<std::string> argv{"sbatch", "--parsable"};
  if (!options.partition.empty()) argv.push_back("--partition=" + options.partition);
  argv.insert(argv.end(), options.sbatch_args.begin(), options.sbatch_args.end());
  return argv;
}

// The array job ids among `ids` that Slurm still queues or runs.
std::set<std::string> active_jobs(const std::set<std::string>& ids, const SlurmOptions& options,
                                  const fs::path& logs) {
  std::set<std::string> active;
  if (ids.empty()) return active;
  std::string list;
  for (const std::string& id : ids) list += (list.empty() ? "" : ",") + id;
  std::string text;
  try {
    text = run_slurm_command({"squeue", "-h", "-o", "%F", "-j", list}, options, logs);
  } catch (const RendererError&) {  // jobs Slurm has forgotten: none active
    return active;
  }
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);)
    if (ids.count(line)) active.insert(line);
  return active;
}

// ---- sorting the renders ----------------------------------------------------------------

struct Sorted {
  std::vector<std::size_t> submit;
  std::size_t failed = 0, queued = 0;
};

Sorted sort_todo(const std::vector<Job>& jobs, const std::vector<std::size_t>& todo,
                 const std::string& study_folder, const RenderCache& cache,
                 const SlurmOptions& options, std::vector<std::string>& errors) {
  const auto batches = read_batches(study_folder);
  std::set<std::string> array_ids;
  for (const auto& [file, b] : batches)
    if (b.contains("array_job") && !b["array_job"].get<std::string>().empty())
      array_ids.insert(b["array_job"].get<std::string>());
  const std::set<std::string> active =
      active_jobs(array_ids, options, slurm_folder(study_folder) / "logs");
  std::set<std::string> queued_keys;
  std::map<std::string, int> submissions;  // in this chain
  for (const auto& [file, b] : batches) {
    const bool is_active = active.count(b.value("array_job", std::string()));
    const bool same_chain = !options.chain.empty() && b.value("chain", "") == options.chain;
    for (const json& j : b["jobs"]) {
      if (is_active) queued_keys.insert(j["key"].get<std::string>());
      if (same_chain) ++submissions[j["key"].get<std::string>()];
    }
  }
  Sorted s;
  for (std::size_t i : todo) {
    const std::string& key = jobs[i].key;
    if (queued_keys.count(key)) {
      ++s.queued;
      continue;
    }
    std::string failure = options.chain.empty() ? "" : read_failure(cache, key);
    if (failure.empty() && submissions[key] >= kMaxSlurmSubmissions)
      failure = fmt::format(
          "submitted {} times to Slurm without a result (task killed, preempted or out of "
          "time?); see {}/logs",
          submissions[key], slurm_folder(study_folder).string());
    if (!failure.empty()) {
      errors[i] = failure;
      ++s.failed;
      continue;
    }
    std::error_code ec;
    fs::remove(failure_path(cache, key), ec);  // a run by hand tries again
    s.submit.push_back(i);
  }
  return s;
}

}  // namespace

SlurmSubmission submit_renders(const std::vector<Job>& jobs, const std::vector<std::size_t>& todo,
                               const std::string& study_folder, const RenderCache& cache,
                               const std::vector<std::pair<RendererKind, RendererIdentity>>& ids,
                               double render_timeout_s, const SlurmOptions& options,
                               std::vector<std::string>& errors) {
  const fs::path folder = fs::absolute(slurm_folder(study_folder));
  fs::create_directories(folder / "logs");
  const Sorted sorted = sort_todo(jobs, todo, study_folder, cache, options, errors);
  SlurmSubmission sub;
  sub.still_queued = sorted.queued;
  if (sorted.submit.empty()) return sub;
  sub.chain = options.chain.empty() ? new_chain() : options.chain;
  json batch{{"format", kBatchFormat},
             {"version", 1},
             {"chain", sub.chain},
             {"study_folder", fs::absolute(study_folder).string()},
             {"timeout_s", render_timeout_s},
             {"renders_per_task", options.renders_per_task},
             {"identities", json::object()},
             {"jobs", json::array()},
             {"array_job", ""},
             {"report_job", ""}};
  for (const auto& [r, id] : ids)
    batch["identities"][to_string(r)] = {{"version", id.version}, {"code_digest", id.code_digest}};
  for (std::size_t i : sorted.submit) batch["jobs"].push_back(job_to_json(jobs[i]));
  const auto now = std::chrono::system_clock::now().time_since_epoch();
  sub.batch_file =
      (folder / fmt::format("batch-{:013d}-{}.json",
                            std::chrono::duration_cast<std::chrono::milliseconds>(now).count(),
                            sub.chain))
          .string();
  write_text_file(sub.batch_file, batch.dump(1) + "\n");
  sub.submitted = sorted.submit.size();
  sub.tasks = static_cast<int>((sub.submitted + options.renders_per_task - 1) /
                               std::size_t(options.renders_per_task));
  const std::string task_script = data_file("harness/slurm_task.sh");
  std::vector<std::string> array = sbatch_common(options);
  array.insert(array.end(),
               {"--job-name=penumbra-render",
                fmt::format("--array=0-{}%{}", sub.tasks - 1, options.array_limit),
                "--output=" + (folder / "logs" / "render-%A_%a.out").string(), task_script,
                options.continue_argv.at(0), "run-batch", sub.batch_file});
  sub.array_job = parse_job_id(run_slurm_command(array, options, folder / "logs"));
  std::vector<std::string> report = sbatch_common(options);
  report.insert(report.end(),
                {"--job-name=penumbra-report", "--dependency=afterany:" + sub.array_job,
                 "--output=" + (folder / "logs" / "report-%j.out").string(), task_script});
  report.insert(report.end(), options.continue_argv.begin(), options.continue_argv.end());
  report.insert(report.end(), {"--slurm-chain", sub.chain});
  sub.report_job = parse_job_id(run_slurm_command(report, options, folder / "logs"));
  batch["array_job"] = sub.array_job;
  batch["report_job"] = sub.report_job;
  write_text_file(sub.batch_file, batch.dump(1) + "\n");
  return sub;
}

namespace {

// The jobs of task `task`, rebuilt from the batch file.
std::vector<Job> task_jobs(const json& batch, int task, const std::string& file) {
  const auto per = batch.at("renders_per_task").get<std::size_t>();
  const json& all = batch.at("jobs");
  const std::size_t first = std::size_t(task) * per;
  if (task < 0 || first >= all.size())
    throw InputError(
        file, "/jobs",
        fmt::format("task {} is out of range ({} renders, {} per task)", task, all.size(), per));
  std::vector<Job> jobs;
  for (std::size_t i = first; i < std::min(all.size(), first + per); ++i) {
    const json& j = all[i];
    Job job;
    job.key = j.at("key");
    job.label = j.at("label");
    job.method = j.at("method");
    job.origin = j.at("origin");
    job.truth = j.at("truth");
    job.variant = j.at("variant");
    const std::optional<RendererKind> r = renderer_from_id(j.at("renderer").get<std::string>());
    if (!r) throw InputError(file, fmt::format("/jobs/{}/renderer", i), "expected a renderer id");
    job.renderer = *r;
    job.scene_json = j.at("scene");
    job.scene = scene_from_json(job.scene_json, job.origin);
    job.representation = job.scene.representation;
    jobs.push_back(std::move(job));
  }
  return jobs;
}

// "" when this node's renderers are the plan's; else why not.
std::string identity_mismatch(const json& batch, const Renderers& here) {
  for (const auto& [r, id] : here.identities) {
    const json& planned = batch.at("identities").at(to_string(r));
    if (planned.at("version") != id.version || planned.at("code_digest") != id.code_digest)
      return fmt::format(
          "this node's {} is \"{}\" with code digest {}, the study was planned with \"{}\" and "
          "{}: install the same version and Penumbra build on every node",
          to_string(r), id.version, id.code_digest, planned.at("version").get<std::string>(),
          planned.at("code_digest").get<std::string>());
  }
  return "";
}

}  // namespace

SlurmTaskResult run_slurm_task(const std::string& batch_file, int task, int threads,
                               const std::function<void(const std::string&)>& log) {
  const json batch = read_json_file(batch_file);
  std::vector<Job> jobs;
  std::string study_folder, mismatch;
  double timeout_s = 0.0;
  Renderers renderers;
  // A batch file is Penumbra's own, but it sits in a shared folder: one that
  // is damaged or hand-edited is bad input naming the file, never a crash.
  try {
    if (!batch.is_object() || batch.value("format", "") != kBatchFormat ||
        batch.value("version", 0) != 1)
      throw InputError(batch_file, "/format", "expected a penumbra-slurm-batch file, version 1");
    jobs = task_jobs(batch, task, batch_file);
    study_folder = batch.at("study_folder").get<std::string>();
    timeout_s = batch.at("timeout_s").get<double>();
    std::vector<RendererKind> kinds;
    for (const Job& j : jobs)
      if (std::find(kinds.begin(), kinds.end(), j.renderer) == kinds.end())
        kinds.push_back(j.renderer);
    const std::string probes =
        (fs::path(study_folder) / "slurm" / fmt::format("versions.{}.json", host_tag())).string();
    renderers = probe_renderers(kinds, std::min(60.0, timeout_s), probes);
    mismatch = identity_mismatch(batch, renderers);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(batch_file, "", std::string("malformed batch file: ") + e.what());
  }
  const RenderCache cache((fs::path(study_folder) / "cache").string());
  BlenderSessions sessions(cache.folder());
  renderers.blender_sessions = &sessions;
  SlurmTaskResult result;
  // The task's renders of one variant's methods share a pass, as locally.
  std::vector<std::size_t> todo;
  for (std::size_t i = 0; i < jobs.size(); ++i)
    if (!cache.contains(jobs[i].key)) todo.push_back(i);
  MethodBatches batches(jobs, todo);
  for (const Job& job : jobs) {
    if (cache.contains(job.key)) {
      ++result.cached;
      continue;
    }
    try {
      if (!mismatch.empty()) throw RendererError(mismatch);
      render_into_cache(job, cache, timeout_s, threads, renderers, &batches);
      ++result.rendered;
      if (log) log("rendered " + job.label);
    } catch (const TaskCancelled&) {
      throw;
    } catch (const std::exception& e) {
      write_text_file(failure_path(cache, job.key), e.what());
      ++result.failed;
      if (log) log(fmt::format("FAILED {}: {}", job.label, printable(e.what(), 300)));
    }
  }
  return result;
}

SlurmStatus slurm_status(const std::string& study_folder) {
  SlurmStatus status;
  const RenderCache cache((fs::path(study_folder) / "cache").string());
  for (const auto& [file, b] : read_batches(study_folder)) {
    SlurmStatus::Batch s;
    s.file = file;
    s.array_job = b.value("array_job", "");
    s.report_job = b.value("report_job", "");
    s.chain = b.value("chain", "");
    for (const json& j : b["jobs"]) {
      ++s.renders;
      const std::string key = j["key"];
      if (cache.contains(key))
        ++s.done;
      else if (fs::exists(failure_path(cache, key)))
        ++s.failed;
    }
    status.batches.push_back(std::move(s));
  }
  status.report_written = fs::exists(fs::path(study_folder) / "report.json");
  return status;
}

}  // namespace penumbra
