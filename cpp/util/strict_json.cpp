#include "util/strict_json.h"

#include <fstream>
#include <set>
#include <sstream>

#include <fmt/format.h>

#include "util/files.h"

namespace penumbra {

using nlohmann::json;

namespace {

// Longest error parts: a file name, a pointer, a message.
constexpr std::size_t kMaxFileChars = 240;
constexpr std::size_t kMaxPointerChars = 160;
constexpr std::size_t kMaxMessageChars = 600;

// Length of the UTF-8 sequence starting at text[i], or 0 if it is not one.
std::size_t utf8_sequence(std::string_view text, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char c = byte(i);
  std::size_t n = 0;
  unsigned lo = 0x80, hi = 0xBF;  // allowed range of the second byte
  if (c < 0x80) return 1;
  if (c >= 0xC2 && c <= 0xDF) n = 2;
  if (c >= 0xE0 && c <= 0xEF) n = 3, lo = c == 0xE0 ? 0xA0 : 0x80, hi = c == 0xED ? 0x9F : 0xBF;
  if (c >= 0xF0 && c <= 0xF4) n = 4, lo = c == 0xF0 ? 0x90 : 0x80, hi = c == 0xF4 ? 0x8F : 0xBF;
  if (n == 0 || i + n > text.size()) return 0;
  if (byte(i + 1) < lo || byte(i + 1) > hi) return 0;
  for (std::size_t k = 2; k < n; ++k)
    if (byte(i + k) < 0x80 || byte(i + k) > 0xBF) return 0;
  return n;
}

// Checks what nlohmann's DOM parser does not: depth, duplicate keys. Builds
// nothing, so a rejected document never exists as a deep tree.
class StrictSax : public nlohmann::json_sax<json> {
 public:
  explicit StrictSax(int max_depth) : max_depth_(max_depth) {}

  bool null() override { return value(); }
  bool boolean(bool) override { return value(); }
  bool number_integer(number_integer_t) override { return value(); }
  bool number_unsigned(number_unsigned_t) override { return value(); }
  bool number_float(number_float_t, const string_t&) override { return value(); }
  bool string(string_t&) override { return value(); }
  bool binary(binary_t&) override { return value(); }
  bool start_object(std::size_t) override { return open(true); }
  bool start_array(std::size_t) override { return open(false); }
  bool end_object() override { return close(); }
  bool end_array() override { return close(); }
  bool key(string_t& k) override {
    Frame& f = stack_.back();
    f.token = pointer_token(k);
    if (!f.keys.insert(k).second)
      return fail(pointer(), "duplicate key (each key may appear once in an object)");
    return true;
  }
  bool parse_error(std::size_t byte, const std::string&,
                   const nlohmann::detail::exception& e) override {
    std::string what = e.what();
    // "[json.exception.parse_error.101] parse error at line 1, column 3: ..."
    if (const auto end = what.find("] "); what.rfind("[json.", 0) == 0 && end != std::string::npos)
      what = what.substr(end + 2);
    return fail("", fmt::format("not valid JSON (byte {}): {}", byte, what));
  }

  const std::optional<std::pair<std::string, std::string>>& error() const { return error_; }

 private:
  struct Frame {
    bool object = false;
    std::size_t next = 0;  // arrays: index of the next element
    std::string token;     // the current element's token
    std::set<std::string> keys;
  };
  bool value() {
    if (!stack_.empty() && !stack_.back().object)
      stack_.back().token = std::to_string(stack_.back().next++);
    return true;
  }
  bool open(bool object) {
    value();
    if (static_cast<int>(stack_.size()) >= max_depth_)
      return fail(pointer(),
                  fmt::format("nested deeper than {} objects and arrays (the limit)", max_depth_));
    stack_.push_back({object, 0, {}, {}});
    return true;
  }
  bool close() {
    stack_.pop_back();
    return true;
  }
  std::string pointer() const {
    std::string p;
    for (const Frame& f : stack_) p += "/" + f.token;
    return p;
  }
  bool fail(std::string pointer, std::string message) {
    if (!error_) error_.emplace(std::move(pointer), std::move(message));
    return false;
  }

  int max_depth_;
  std::vector<Frame> stack_;
  std::optional<std::pair<std::string, std::string>> error_;
};

// nullopt: valid; otherwise (pointer, message).
std::optional<std::pair<std::string, std::string>> check_text(const std::string& text) {
  if (const auto nul = text.find('\0'); nul != std::string::npos)
    return std::make_pair(
        std::string(),
        fmt::format("not valid JSON (byte {}): a NUL byte (JSON text has none)", nul));
  StrictSax sax(kMaxJsonDepth);
  const bool ok = json::sax_parse(text, &sax, json::input_format_t::json, /*strict=*/true);
  if (!ok && !sax.error()) return std::make_pair(std::string(), std::string("not valid JSON"));
  return sax.error();
}

void describe_into(const json& j, std::size_t max_chars, int depth, std::string& out) {
  if (out.size() > max_chars) return;
  if (depth > 8) {
    out += "...";
    return;
  }
  if (j.is_object() || j.is_array()) {
    out += j.is_object() ? '{' : '[';
    bool first = true;
    for (auto it = j.begin(); it != j.end() && out.size() <= max_chars; ++it) {
      if (!first) out += ',';
      first = false;
      if (j.is_object()) out += "\"" + printable(it.key(), max_chars) + "\":";
      describe_into(*it, max_chars, depth + 1, out);
    }
    out += j.is_object() ? '}' : ']';
  } else if (j.is_string()) {
    out += "\"" + printable(j.get_ref<const std::string&>(), max_chars) + "\"";
  } else {
    out += j.dump();  // a scalar: short
  }
}

}  // namespace

InputError::InputError(const std::string& file, const std::string& pointer,
                       const std::string& message)
    : std::runtime_error(pointer.empty() ? fmt::format("{}: {}", printable(file, kMaxFileChars),
                                                       printable(message, kMaxMessageChars))
                                         : fmt::format("{}: {}: {}", printable(file, kMaxFileChars),
                                                       printable(pointer, kMaxPointerChars),
                                                       printable(message, kMaxMessageChars))),
      file_(file),
      pointer_(pointer),
      reason_(message) {}

std::string printable(std::string_view text, std::size_t max_chars) {
  std::string out;
  std::size_t i = 0;
  while (i < text.size()) {
    if (out.size() >= max_chars) {
      out += "...";
      break;
    }
    const auto c = static_cast<unsigned char>(text[i]);
    const std::size_t n = utf8_sequence(text, i);
    if (c == '\n') {
      out += "\\n";
    } else if (c == '\t') {
      out += "\\t";
    } else if (c < 0x20 || c == 0x7F || n == 0) {
      out += fmt::format("\\x{:02x}", c);
    } else {
      out.append(text.substr(i, n));
      i += n;
      continue;
    }
    ++i;
  }
  return out;
}

std::string describe_json(const json& value, std::size_t max_chars) {
  std::string out;
  describe_into(value, max_chars, 0, out);
  if (out.size() > max_chars) out = out.substr(0, max_chars - 3) + "...";
  return out;
}

std::string pointer_token(std::string_view key) {
  std::string escaped;
  for (char c : key) escaped += c == '~' ? "~0" : (c == '/' ? "~1" : std::string(1, c));
  return escaped;
}

std::vector<std::string> pointer_tokens(std::string_view pointer) {
  std::vector<std::string> tokens;
  if (pointer.empty()) return tokens;
  if (pointer[0] != '/') throw std::invalid_argument("a JSON pointer starts with '/'");
  std::string token;
  for (std::size_t i = 1; i <= pointer.size(); ++i) {
    if (i == pointer.size() || pointer[i] == '/') {
      tokens.push_back(std::move(token));
      token.clear();
    } else if (pointer[i] == '~') {
      if (i + 1 >= pointer.size() || (pointer[i + 1] != '0' && pointer[i + 1] != '1'))
        throw std::invalid_argument("'~' must be followed by 0 or 1 in a JSON pointer");
      token += pointer[++i] == '0' ? '~' : '/';
    } else {
      token += pointer[i];
    }
  }
  return tokens;
}

json parse_json_text(const std::string& text, const std::string& origin) {
  if (const auto error = check_text(text)) throw InputError(origin, error->first, error->second);
  try {
    return json::parse(text);
  } catch (const json::exception& e) {  // not expected after the check; never a crash
    throw InputError(origin, "", std::string("not valid JSON: ") + e.what());
  }
}

std::optional<json> parse_json_value_or_word(const std::string& text, const std::string& origin,
                                             const std::string& pointer) {
  const auto error = check_text(text);
  if (!error) return json::parse(text);
  // Syntax errors make a bare word; a valid text that breaks a rule does not.
  if (!error->first.empty() || error->second.find("nested deeper") != std::string::npos)
    throw InputError(origin, pointer + error->first, error->second);
  return std::nullopt;
}

json read_json_file(const std::string& path) {
  if (const std::string problem = input_file_problem(path); !problem.empty())
    throw InputError(path, "", "cannot open the file for reading: " + problem);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", "cannot open the file for reading");
  std::stringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw InputError(path, "", "cannot read the file");
  return parse_json_text(buffer.str(), path);
}

bool is_utf8(std::string_view text) {
  for (std::size_t i = 0; i < text.size();) {
    const std::size_t n = utf8_sequence(text, i);
    if (n == 0) return false;
    i += n;
  }
  return true;
}

}  // namespace penumbra
