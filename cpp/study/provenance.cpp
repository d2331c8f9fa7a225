#include "study/provenance.h"

#include <sys/utsname.h>

#include <chrono>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <thread>

#include <fmt/format.h>

#include "util/build_info.h"
#include "util/sha256.h"
#include "util/version.h"

namespace penumbra {
namespace {

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("model name", 0) == 0) {
      const std::size_t colon = line.find(':');
      if (colon != std::string::npos) return line.substr(line.find_first_not_of(" \t", colon + 1));
    }
  return "unknown";
}

std::string system_name() {
  struct utsname u {};
  if (::uname(&u) != 0) return "unknown";
  return fmt::format("{} {} {}", u.sysname, u.release, u.machine);
}

// Now, or SOURCE_DATE_EPOCH where it is set (the reproducible-builds
// convention: a report that must be byte-identical across runs pins it).
std::string utc_now() {
  std::time_t t = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  if (const char* epoch = std::getenv("SOURCE_DATE_EPOCH")) {
    char* end = nullptr;
    const long long pinned = std::strtoll(epoch, &end, 10);
    if (end != epoch && *end == '\0' && pinned >= 0) t = static_cast<std::time_t>(pinned);
  }
  std::tm tm{};
  gmtime_r(&t, &tm);
  char text[32];
  std::strftime(text, sizeof(text), "%Y-%m-%dT%H:%M:%SZ", &tm);
  return text;
}

}  // namespace

Provenance collect_provenance(const std::string& study_file,
                              const std::map<RendererKind, std::string>& renderer_versions) {
  Provenance p;
  p.version = kPenumbraVersion;
  p.commit = build_commit();
  p.dirty = build_dirty();
  p.date = utc_now();
  p.cpu = cpu_model();
  p.cores = std::thread::hardware_concurrency();
  p.system = system_name();
  p.renderers = renderer_versions;
  p.renderers[RendererKind::kEvaluator] = kPenumbraVersion;
  p.study_sha256 = sha256_file_hex(study_file);
  return p;
}

nlohmann::json provenance_json(const Provenance& p) {
  nlohmann::json renderers = nlohmann::json::object();
  for (const auto& [r, version] : p.renderers) renderers[renderer_info(r).id] = version;
  return {{"penumbra", p.version},
          {"commit", p.commit},
          {"dirty", p.dirty < 0 ? nlohmann::json() : nlohmann::json(p.dirty == 1)},
          {"date", p.date},
          {"machine", {{"cpu", p.cpu}, {"cores", p.cores}, {"system", p.system}}},
          {"renderers", renderers},
          {"study_sha256", p.study_sha256}};
}

std::string without_run_keys(const std::string& text) {
  nlohmann::json doc = nlohmann::json::parse(text, nullptr, false);
  if (doc.is_discarded() || !doc.is_object()) return text;
  doc.erase("provenance");
  doc.erase("seconds");
  return doc.dump();
}

}  // namespace penumbra
