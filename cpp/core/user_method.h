// Terminator factors defined outside the method table: a user's function,
// registered while the process runs (from Python: penumbra.method,
// docs/python.md), that a render calls on batches of samples rather than
// per sample. The table's row `python` (core/terminator.h) stands for all
// of them; a scene or a study names one by the id it was registered under.
#pragma once

#include <functional>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "core/vec.h"

namespace penumbra {

// A batch of samples, the factor's inputs, one entry per sample. The
// cosines are those of core/terminator.h's vectors: cos_light = <ng,wi>,
// cos_deviation = <ng,ns>, cos_shading = <ns,wi>, cos_view = <ng,wo>,
// ng the factor's reference normal (Ng, or Ni where the scene says so).
// The vectors themselves are filled only for a method that asks for them
// (UserMethod::wants_vectors); otherwise they are empty.
struct FactorBatch {
  std::span<const double> cos_light, cos_deviation, cos_shading, cos_view;
  std::span<const Vec3> ng, ns, wi, wo;
  std::size_t size() const { return cos_light.size(); }
};

// A scalar parameter of a user method: its value comes from the scene's
// /terminator/parameters/<name>, checked against [min_value, max_value].
struct UserParameter {
  std::string name;
  double default_value = 0.0;
  double min_value = -1e300, max_value = 1e300;
  std::string description;  // the unit and the domain, as the user wrote them
};

struct UserMethod {
  std::string id;      // what scenes and studies name; never a built-in id
  std::string source;  // where it is defined, e.g. "my_terms.py:my_term"
  // A digest of the definition (the source file's content and the
  // function's name): part of every render's cache key, so that editing the
  // function renders again.
  std::string digest;
  std::vector<UserParameter> parameters;
  double min_value = 0.0, max_value = 1.0;  // the declared range of G
  bool wants_vectors = false;
  // G for every sample of the batch into g (g.size() == batch.size());
  // `values`: the parameters' values, in the order of `parameters`. Throws
  // std::runtime_error with the reason when the function fails. Called
  // from one of the render's threads, outside its parallel loops.
  std::function<void(const FactorBatch& batch, std::span<const double> values, std::span<double> g)>
      factor;
};

// A user method's function failed, or returned what it may not (the reason
// names the method, the sample and the value).
class UserMethodError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Registers (or replaces, by id) a user method. std::invalid_argument for
// a built-in id or an id that is not lower-case letters, digits and '-'.
void register_user_method(std::shared_ptr<const UserMethod> method);
// nullptr where no method has that id.
std::shared_ptr<const UserMethod> find_user_method(std::string_view id);
std::vector<std::string> user_method_ids();

// Calls the method's function on `batch` and checks what it returned:
// every value finite and within [min_value, max_value]. UserMethodError
// otherwise (the function's own failure included).
void evaluate_user_method(const UserMethod& method, const FactorBatch& batch,
                          std::span<const double> values, std::span<double> g);

}  // namespace penumbra
