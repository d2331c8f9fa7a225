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
#include "study/convergence.h"
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
constexpr int kBatchVersion = 2;  // 2: the task table, convergence chains

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
  return {
      {"key", job.key},         {"label", job.label},       {"renderer", to_string(job.renderer)},
      {"method", job.method},   {"origin", job.origin()},   {"truth", job.truth},
      {"variant", job.variant}, {"scene", job.scene_json()}};
}

json chain_to_json(const SlurmChain& c) {
  json then = json::array();
  for (const Job& j : c.then) then.push_back(job_to_json(j));
  return {{"truth", job_to_json(c.truth)},
          {"edge_steps", c.edge_steps},
          {"spp_steps", c.spp_steps},
          {"tolerance", c.settings.tolerance},
          {"max_edge_refinements", c.settings.max_edge_refinements},
          {"max_spp_refinements", c.settings.max_spp_refinements},
          {"max_memory_bytes", c.max_memory_bytes},
          {"then", std::move(then)}};
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

// Submits `argv` (an sbatch call) for the batch file `batch_file`; when
// sbatch fails, nothing was submitted, so the batch file goes too (else
// `penumbra status` would show a submission that never was).
std::string submit_or_forget(const std::vector<std::string>& argv, const SlurmOptions& options,
                             const fs::path& logs, const std::string& batch_file) {
  try {
    return parse_job_id(run_slurm_command(argv, options, logs));
  } catch (const RendererError&) {
    std::error_code ec;
    fs::remove(batch_file, ec);
    throw;
  }
}

// The report job of `sub` was refused: without it nothing would continue
// the study after the array, so the array is cancelled and its batch file
// removed (a rerun submits its renders once more). When scancel fails too,
// the array stays recorded: a rerun then counts its renders as queued
// rather than submitting them twice. Returns the message to report.
std::string withdraw_array(const std::string& why, const SlurmSubmission& sub,
                           const SlurmOptions& options, const fs::path& logs) {
  try {
    run_slurm_command({"scancel", sub.array_job}, options, logs);
  } catch (const RendererError& e) {
    return fmt::format(
        "{}; array job {} was submitted and could not be cancelled ({}): it is recorded in {}, "
        "run the study again once it has ended",
        why, sub.array_job, e.what(), sub.batch_file);
  }
  std::error_code ec;
  fs::remove(sub.batch_file, ec);
  return fmt::format("{}; array job {} was cancelled, nothing stays submitted", why, sub.array_job);
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

// The chain whose batch entry is `key`, or null.
const SlurmChain* find_chain(const SlurmChains* chains, const std::string& key) {
  if (!chains) return nullptr;
  const auto it = chains->by_key.find(key);
  return it != chains->by_key.end() ? &it->second : nullptr;
}

// A chain renders one check after another: an array task of its own each,
// first; the other renders in tasks of up to `per`, in plan order, a mesh's
// renders together (slurm_task_ranges). `tasks` lists
// each task's [first, count) of `jobs`.
void add_entries(const std::vector<Job>& jobs, const std::vector<std::size_t>& submit,
                 const SlurmChains* chains, int per, json& batch, SlurmSubmission& sub) {
  std::vector<std::size_t> plain;
  for (std::size_t i : submit) {
    const SlurmChain* chain = find_chain(chains, jobs[i].key);
    if (!chain) {
      plain.push_back(i);
      continue;
    }
    json entry = job_to_json(jobs[i]);
    entry["chain"] = chain_to_json(*chain);
    batch["tasks"].push_back({batch["jobs"].size(), 1});
    batch["jobs"].push_back(std::move(entry));
    ++sub.chains;
  }
  std::vector<std::string> keys;
  for (std::size_t i : plain) keys.push_back(render_group_key(jobs[i]));
  for (const auto& [first, count] : slurm_task_ranges(keys, per)) {
    batch["tasks"].push_back({batch["jobs"].size(), count});
    for (std::size_t m = first; m < first + count; ++m)
      batch["jobs"].push_back(job_to_json(jobs[plain[m]]));
  }
  sub.submitted = submit.size();
  sub.tasks = static_cast<int>(batch["tasks"].size());
}

// ---- sorting the renders ----------------------------------------------------------------

struct Sorted {
  std::vector<std::size_t> submit;
  std::size_t failed = 0, queued = 0;
};

// What earlier submissions say about a render: queued in an array that still
// runs (or, for a chain, its variant's chain is), and how often this chain of
// submissions has asked for it.
struct History {
  std::set<std::string> queued_keys, queued_truths;
  std::map<std::string, int> submissions;
};

History read_history(const std::string& study_folder, const SlurmOptions& options) {
  const auto batches = read_batches(study_folder);
  std::set<std::string> array_ids;
  for (const auto& [file, b] : batches)
    if (b.contains("array_job") && !b["array_job"].get<std::string>().empty())
      array_ids.insert(b["array_job"].get<std::string>());
  const std::set<std::string> active =
      active_jobs(array_ids, options, slurm_folder(study_folder) / "logs");
  History h;
  for (const auto& [file, b] : batches) {
    const bool is_active = active.count(b.value("array_job", std::string()));
    const bool same_chain = !options.chain.empty() && b.value("chain", "") == options.chain;
    for (const json& j : b["jobs"]) {
      if (is_active) h.queued_keys.insert(j["key"].get<std::string>());
      if (is_active && j.contains("chain"))
        h.queued_truths.insert(j["chain"]["truth"]["key"].get<std::string>());
      if (same_chain) ++h.submissions[j["key"].get<std::string>()];
    }
  }
  return h;
}

// Why `key` must not be submitted again: a failure this chain of submissions
// recorded, or too many submissions without a result; "" when it may be.
std::string given_up(const std::string& key, const History& h, const std::string& study_folder,
                     const RenderCache& cache, const SlurmOptions& options) {
  std::string failure = options.chain.empty() ? "" : read_failure(cache, key);
  const auto asked = h.submissions.find(key);
  if (failure.empty() && asked != h.submissions.end() && asked->second >= kMaxSlurmSubmissions)
    failure = fmt::format(
        "submitted {} times to Slurm without a result (task killed, preempted or out of "
        "time?); see {}/logs",
        asked->second, slurm_folder(study_folder).string());
  return failure;
}

Sorted sort_todo(const std::vector<Job>& jobs, const std::vector<std::size_t>& todo,
                 const std::string& study_folder, const RenderCache& cache,
                 const SlurmOptions& options, const SlurmChains* chains,
                 std::vector<std::string>& errors) {
  const History h = read_history(study_folder, options);
  Sorted s;
  std::set<std::string> taken;  // keys submitted now or left to a queued chain
  std::vector<std::size_t> covered;
  for (std::size_t i : todo) {
    const std::string& key = jobs[i].key;
    if (chains && chains->covered.count(key)) {
      covered.push_back(i);
      continue;
    }
    const SlurmChain* chain = find_chain(chains, key);
    if (h.queued_keys.count(key) || (chain && h.queued_truths.count(chain->truth.key))) {
      ++s.queued;
      taken.insert(key);
      continue;
    }
    if (std::string failure = given_up(key, h, study_folder, cache, options); !failure.empty()) {
      errors[i] = std::move(failure);
      ++s.failed;
      continue;
    }
    std::error_code ec;
    fs::remove(failure_path(cache, key), ec);  // a run by hand tries again
    s.submit.push_back(i);
    taken.insert(key);
  }
  // A chain's other checks are its to render, unless the chain itself is
  // not going (given up): then they are renders like any other.
  for (std::size_t i : covered) {
    const std::string& key = jobs[i].key;
    if (taken.count(chains->covered.at(key))) continue;
    if (std::string failure = given_up(key, h, study_folder, cache, options); !failure.empty()) {
      errors[i] = std::move(failure);
      ++s.failed;
    } else if (h.queued_keys.count(key)) {
      ++s.queued;
    } else {
      s.submit.push_back(i);
    }
  }
  return s;
}

}  // namespace

std::vector<std::pair<std::size_t, std::size_t>> slurm_task_ranges(
    const std::vector<std::string>& keys, int per) {
  const std::size_t n = keys.size(), most = std::size_t(std::max(per, 1));
  std::vector<std::pair<std::size_t, std::size_t>> tasks;
  std::size_t start = 0;  // of the task being filled
  for (std::size_t i = 0; i < n;) {
    std::size_t end = i + 1;  // of the group at i
    if (!keys[i].empty())
      while (end < n && keys[end] == keys[i]) ++end;
    if (i > start && end - start > most) {  // the group starts a task of its own
      tasks.emplace_back(start, i - start);
      start = i;
    }
    for (; end - start > most; start += most) tasks.emplace_back(start, most);
    i = end;
  }
  if (start < n) tasks.emplace_back(start, n - start);
  return tasks;
}

SlurmSubmission submit_renders(const std::vector<Job>& jobs, const std::vector<std::size_t>& todo,
                               const std::string& study_folder, const RenderCache& cache,
                               const std::vector<std::pair<RendererKind, RendererIdentity>>& ids,
                               double render_timeout_s, const SlurmOptions& options,
                               std::vector<std::string>& errors, const SlurmChains* chains) {
  const fs::path folder = fs::absolute(slurm_folder(study_folder));
  fs::create_directories(folder / "logs");
  const Sorted sorted = sort_todo(jobs, todo, study_folder, cache, options, chains, errors);
  SlurmSubmission sub;
  sub.still_queued = sorted.queued;
  if (sorted.submit.empty()) return sub;
  sub.chain = options.chain.empty() ? new_chain() : options.chain;
  json batch{{"format", kBatchFormat},
             {"version", kBatchVersion},
             {"chain", sub.chain},
             {"study_folder", fs::absolute(study_folder).string()},
             {"timeout_s", render_timeout_s},
             {"renders_per_task", options.renders_per_task},
             {"identities", json::object()},
             {"jobs", json::array()},
             {"tasks", json::array()},
             {"array_job", ""},
             {"report_job", ""}};
  for (const auto& [r, id] : ids)
    batch["identities"][to_string(r)] = {{"version", id.version}, {"code_digest", id.code_digest}};
  add_entries(jobs, sorted.submit, chains, options.renders_per_task, batch, sub);
  const auto now = std::chrono::system_clock::now().time_since_epoch();
  sub.batch_file =
      (folder / fmt::format("batch-{:013d}-{}.json",
                            std::chrono::duration_cast<std::chrono::milliseconds>(now).count(),
                            sub.chain))
          .string();
  write_text_file(sub.batch_file, batch.dump(1) + "\n");
  const std::string task_script = data_file("harness/slurm_task.sh");
  std::vector<std::string> array = sbatch_common(options);
  array.insert(array.end(),
               {"--job-name=penumbra-render",
                fmt::format("--array=0-{}%{}", sub.tasks - 1, options.array_limit),
                "--output=" + (folder / "logs" / "render-%A_%a.out").string(), task_script,
                options.continue_argv.at(0), "run-batch", sub.batch_file});
  sub.array_job = submit_or_forget(array, options, folder / "logs", sub.batch_file);
  // Recorded before the report job is asked for, so that whatever happens
  // next, a rerun sees these renders queued and does not submit them again.
  batch["array_job"] = sub.array_job;
  write_text_file(sub.batch_file, batch.dump(1) + "\n");
  std::vector<std::string> report = sbatch_common(options);
  report.insert(report.end(),
                {"--job-name=penumbra-report", "--dependency=afterany:" + sub.array_job,
                 "--output=" + (folder / "logs" / "report-%j.out").string(), task_script});
  report.insert(report.end(), options.continue_argv.begin(), options.continue_argv.end());
  report.insert(report.end(), {"--slurm-chain", sub.chain});
  try {
    sub.report_job = parse_job_id(run_slurm_command(report, options, folder / "logs"));
  } catch (const RendererError& e) {
    throw RendererError(withdraw_array(e.what(), sub, options, folder / "logs"));
  }
  batch["report_job"] = sub.report_job;
  write_text_file(sub.batch_file, batch.dump(1) + "\n");
  return sub;
}

namespace {

// A cache key as render_key() writes it; anything else (a path, "zz") is
// refused before it can name a file.
bool is_render_key(const std::string& key) {
  static const std::regex format("[0-9a-f]{32}");
  return std::regex_match(key, format);
}

Job job_from_json(const json& j, const std::string& file, const std::string& pointer) {
  Job job;
  job.key = j.at("key");
  job.label = j.at("label");
  job.method = j.at("method");
  job.truth = j.at("truth");
  job.variant = j.at("variant");
  const std::optional<RendererKind> r = renderer_from_id(j.at("renderer").get<std::string>());
  if (!r) throw InputError(file, pointer + "/renderer", "expected a renderer id");
  job.renderer = *r;
  std::string origin = j.at("origin");
  Scene scene = scene_from_json(j.at("scene"), origin);
  job.set_scene(j.at("scene"), std::move(scene), std::move(origin));
  return job;
}

SlurmChain chain_from_json(const json& c, const std::string& file, const std::string& pointer) {
  SlurmChain chain;
  chain.truth = job_from_json(c.at("truth"), file, pointer + "/truth");
  chain.edge_steps = c.at("edge_steps");
  chain.spp_steps = c.at("spp_steps");
  chain.settings.tolerance = c.at("tolerance");
  chain.settings.max_edge_refinements = c.at("max_edge_refinements");
  chain.settings.max_spp_refinements = c.at("max_spp_refinements");
  chain.max_memory_bytes = c.at("max_memory_bytes");
  const json& then = c.at("then");
  for (std::size_t k = 0; k < then.size(); ++k)
    chain.then.push_back(job_from_json(then[k], file, fmt::format("{}/then/{}", pointer, k)));
  return chain;
}

// One entry of a task: a render, or a convergence chain (its first check).
struct TaskEntry {
  Job job;
  std::optional<SlurmChain> chain;
  std::string pointer;  // its place in the batch file, "/jobs/N"
};

// The identities the study was planned with, as the batch file records them.
std::vector<std::pair<RendererKind, RendererIdentity>> planned_identities(const json& batch) {
  std::vector<std::pair<RendererKind, RendererIdentity>> ids;
  for (const auto& [id, planned] : batch.at("identities").items())
    if (const std::optional<RendererKind> r = renderer_from_id(id))
      ids.push_back({*r, {planned.at("version"), planned.at("code_digest")}});
  return ids;
}

// Every entry's key recomputed from its scene: a scene edited after
// planning must not be cached under the key of the scene that was planned,
// where the next `penumbra run` would take it for that one.
void check_keys(const std::vector<TaskEntry>& entries, const json& batch, const std::string& file) {
  const auto ids = planned_identities(batch);
  for (const TaskEntry& e : entries) {
    if (!is_render_key(e.job.key))
      throw InputError(file, e.pointer + "/key",
                       fmt::format("expected a cache key of 32 hex digits, got \"{}\"",
                                   printable(e.job.key, 80)));
    std::vector<Job> recomputed{e.job};
    assign_keys(recomputed, ids);
    if (recomputed[0].key != e.job.key)
      throw InputError(file, e.pointer + "/key",
                       fmt::format("the batch file gives key {}, but the scene beside it has key "
                                   "{} (edited after planning?): submit the study again",
                                   e.job.key, recomputed[0].key));
  }
}

// The entries of task `task`, rebuilt from the batch file.
std::vector<TaskEntry> task_entries(const json& batch, int task, const std::string& file) {
  const json& tasks = batch.at("tasks");
  const json& all = batch.at("jobs");
  if (task < 0 || std::size_t(task) >= tasks.size())
    throw InputError(file, "/tasks",
                     fmt::format("task {} is out of range ({} tasks)", task, tasks.size()));
  const auto first = tasks[task].at(0).get<std::size_t>();
  const auto count = tasks[task].at(1).get<std::size_t>();
  if (first + count > all.size())
    throw InputError(file, fmt::format("/tasks/{}", task),
                     fmt::format("expected renders within the {} of /jobs", all.size()));
  std::vector<TaskEntry> entries;
  for (std::size_t i = first; i < first + count; ++i) {
    const std::string pointer = fmt::format("/jobs/{}", i);
    TaskEntry e{job_from_json(all[i], file, pointer), std::nullopt, pointer};
    if (all[i].contains("chain"))
      e.chain = chain_from_json(all[i]["chain"], file, pointer + "/chain");
    entries.push_back(std::move(e));
  }
  return entries;
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

// What every render of one array task shares.
struct TaskContext {
  const RenderCache& cache;
  const Renderers& renderers;
  std::string mismatch;  // why this node must not render, if it must not
  double timeout_s = 0.0;
  int threads = 1;
  const std::function<void(const std::string&)>& log;
  SlurmTaskResult& result;
};

// `job` from the cache, else rendered into it; a failure is recorded beside
// its entry, in `error` and the result, and gives nullopt.
std::optional<Image> cached_or_rendered(const Job& job, TaskContext& t, MethodBatches* batches,
                                        std::string* error = nullptr) {
  if (t.cache.contains(job.key)) {
    std::string reason;
    if (std::optional<Image> image = t.cache.lookup(job.key, &reason)) {
      ++t.result.cached;
      return image;
    }
    t.cache.remove(job.key);  // damaged: rendered again
  }
  try {
    if (!t.mismatch.empty()) throw RendererError(t.mismatch);
    Image image = render_into_cache(job, t.cache, t.timeout_s, t.threads, t.renderers, batches);
    ++t.result.rendered;
    if (t.log) t.log("rendered " + job.label);
    return image;
  } catch (const TaskCancelled&) {
    throw;
  } catch (const std::exception& e) {
    write_text_file(failure_path(t.cache, job.key), e.what());
    ++t.result.failed;
    if (t.log) t.log(fmt::format("FAILED {}: {}", job.label, printable(e.what(), 300)));
    if (error) *error = e.what();
  }
  return std::nullopt;
}

// The renders of `jobs` missing from the cache, a variant's methods in one pass.
void render_missing(const std::vector<Job>& jobs, TaskContext& t) {
  std::vector<std::size_t> todo;
  for (std::size_t i = 0; i < jobs.size(); ++i)
    if (!t.cache.contains(jobs[i].key)) todo.push_back(i);
  MethodBatches batches(jobs, todo);
  for (const Job& job : jobs) {
    if (t.cache.contains(job.key)) {
      ++t.result.cached;
      continue;
    }
    cached_or_rendered(job, t, &batches);
  }
}

// The rest of a variant's convergence chain, then its evaluator jobs at the
// settings reached: the renders the next `penumbra run` will look up.
void run_chain(const SlurmChain& chain, TaskContext& t) {
  const RenderBatch render = [&](const std::vector<Job>& jobs, const std::vector<ChainState>&,
                                 std::vector<std::string>* errors) {
    std::vector<Job> keyed = jobs;
    assign_keys(keyed, t.renderers.identities);
    errors->assign(keyed.size(), "");
    std::vector<std::optional<Image>> images(keyed.size());
    for (std::size_t i = 0; i < keyed.size(); ++i)
      images[i] = cached_or_rendered(keyed[i], t, nullptr, &(*errors)[i]);
    return images;
  };
  const VariantConvergence reached = continue_chain(chain.truth, chain.edge_steps, chain.spp_steps,
                                                    chain.settings, chain.max_memory_bytes, render);
  if (t.log)
    t.log(fmt::format("{}: {} at edge length {:g}, {} spp", chain.truth.label,
                      reached.converged ? "converged" : "not converged", reached.edge_length,
                      reached.spp));
  std::vector<Job> then = chain.then;
  for (Job& job : then) apply_convergence(job, reached);
  assign_keys(then, t.renderers.identities);
  render_missing(then, t);
}

}  // namespace

SlurmTaskResult run_slurm_task(const std::string& batch_file, int task, int threads,
                               const std::function<void(const std::string&)>& log) {
  const json batch = read_json_file(batch_file);
  std::vector<TaskEntry> entries;
  std::string study_folder, mismatch;
  double timeout_s = 0.0;
  Renderers renderers;
  // A batch file is Penumbra's own, but it sits in a shared folder: one that
  // is damaged or hand-edited is bad input naming the file, never a crash.
  try {
    if (!batch.is_object() || batch.value("format", "") != kBatchFormat ||
        batch.value("version", 0) != kBatchVersion)
      throw InputError(batch_file, "/format",
                       fmt::format("expected a penumbra-slurm-batch file, version {} (one written "
                                   "by another Penumbra version: submit the study again)",
                                   kBatchVersion));
    entries = task_entries(batch, task, batch_file);
    check_keys(entries, batch, batch_file);
    study_folder = batch.at("study_folder").get<std::string>();
    timeout_s = batch.at("timeout_s").get<double>();
    std::vector<RendererKind> kinds;
    for (const TaskEntry& e : entries)
      if (std::find(kinds.begin(), kinds.end(), e.job.renderer) == kinds.end())
        kinds.push_back(e.job.renderer);
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
  TaskContext context{cache, renderers, mismatch, timeout_s, threads, log, result};
  std::vector<Job> renders;
  for (const TaskEntry& e : entries) {
    if (e.chain)
      run_chain(*e.chain, context);
    else
      renders.push_back(e.job);
  }
  render_missing(renders, context);
  return result;
}

SlurmStatus slurm_status(const std::string& study_folder) {
  SlurmStatus status;
  const RenderCache cache((fs::path(study_folder) / "cache").string());
  for (const auto& [file, b] : read_batches(study_folder)) {
    SlurmStatus::Batch s;
    s.file = file;
    s.array_job = b.value("array_job", "");
    // Written just before its sbatch call, by a submitter killed before
    // the call answered: never known to Slurm, nothing to show.
    if (s.array_job.empty()) continue;
    s.report_job = b.value("report_job", "");
    s.chain = b.value("chain", "");
    for (const json& j : b["jobs"]) {
      if (j.contains("chain")) {  // how far it got shows in the renders the report job finds
        ++s.chains;
        continue;
      }
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
