#include "core/user_method.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <mutex>
#include <string>

#include "core/terminator.h"

namespace penumbra {
namespace {

struct Registry {
  std::mutex mutex;
  std::map<std::string, std::shared_ptr<const UserMethod>, std::less<>> methods;
};

Registry& registry() {
  static Registry r;
  return r;
}

std::string number(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", x);
  return text;
}

bool valid_id(std::string_view id) {
  return !id.empty() && std::all_of(id.begin(), id.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-';
  });
}

}  // namespace

void register_user_method(std::shared_ptr<const UserMethod> method) {
  if (!method || !method->factor) throw std::invalid_argument("register_user_method: no function");
  if (!valid_id(method->id))
    throw std::invalid_argument("a user method's id is lower-case letters, digits and '-', got \"" +
                                method->id + "\"");
  for (const MethodInfo& info : all_methods())
    if (info.id == method->id)
      throw std::invalid_argument("\"" + method->id + "\" is a built-in method's id");
  Registry& r = registry();
  std::lock_guard<std::mutex> lock(r.mutex);
  r.methods[method->id] = std::move(method);
}

std::shared_ptr<const UserMethod> find_user_method(std::string_view id) {
  Registry& r = registry();
  std::lock_guard<std::mutex> lock(r.mutex);
  const auto it = r.methods.find(id);
  return it == r.methods.end() ? nullptr : it->second;
}

std::vector<std::string> user_method_ids() {
  Registry& r = registry();
  std::lock_guard<std::mutex> lock(r.mutex);
  std::vector<std::string> ids;
  for (const auto& entry : r.methods) ids.push_back(entry.first);
  return ids;
}

void evaluate_user_method(const UserMethod& method, const FactorBatch& batch,
                          std::span<const double> values, std::span<double> g) {
  try {
    method.factor(batch, values, g);
  } catch (const UserMethodError&) {
    throw;
  } catch (const std::exception& e) {
    throw UserMethodError("user method \"" + method.id + "\" (" + method.source +
                          ") failed: " + e.what());
  }
  for (std::size_t k = 0; k < g.size(); ++k)
    if (!std::isfinite(g[k]) || g[k] < method.min_value || g[k] > method.max_value)
      throw UserMethodError("user method \"" + method.id + "\" (" + method.source + ") returned " +
                            number(g[k]) + " at sample " + std::to_string(k) + " of a batch of " +
                            std::to_string(g.size()) + ": expected a finite value in [" +
                            number(method.min_value) + ", " + number(method.max_value) + "]");
}

}  // namespace penumbra
