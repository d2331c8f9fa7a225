// Reading JSON text that may be hostile: every way in (scene files, --set
// values, study files, EXR metadata) goes through here, so that no input can
// crash the program (unbounded nesting, NUL bytes) or pass silently as
// something it is not (duplicate keys, numbers outside double's range).
// Errors are one printable line naming the file, the JSON pointer and what was
// expected.
#pragma once

#include <cstddef>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

namespace penumbra {

// Deepest nesting of objects and arrays accepted anywhere. Scene files nest
// 4 levels; 64 leaves room for any hand-written file while keeping the
// recursive serialiser and destructor far from the stack's end.
inline constexpr int kMaxJsonDepth = 64;

// Bad input. what() is one printable line: "FILE: /json/pointer: expected ...,
// got ..." ("FILE: message" where no pointer applies). Control characters and
// invalid UTF-8 are escaped and every part is truncated, so a hostile key or
// value cannot spill escapes or megabytes onto the terminal.
class InputError : public std::runtime_error {
 public:
  InputError(const std::string& file, const std::string& pointer, const std::string& message);
  const std::string& file() const { return file_; }
  const std::string& pointer() const { return pointer_; }
  // What was expected, without the file and pointer (the Python module's
  // SceneError carries the three apart).
  const std::string& reason() const { return reason_; }

 private:
  std::string file_, pointer_, reason_;
};

// `text` with control characters, DEL and bytes that are not UTF-8 written as
// \n, \t, \xHH; cut to at most `max_chars` output characters with "...".
std::string printable(std::string_view text, std::size_t max_chars);

// A JSON value for an error message: at most `max_chars` characters, printable,
// without serialising more of a large value than it shows.
std::string describe_json(const nlohmann::json& value, std::size_t max_chars = 60);

// RFC 6901 reference token of an object key ('~' -> "~0", '/' -> "~1").
std::string pointer_token(std::string_view key);
// The tokens of a JSON pointer ("" -> none); throws std::invalid_argument when
// it does not start with '/' or has a bad '~' escape.
std::vector<std::string> pointer_tokens(std::string_view pointer);

// Parses JSON text strictly: no NUL bytes, nesting at most kMaxJsonDepth,
// no duplicate keys in an object, finite numbers. Throws InputError(origin,
// pointer or "", message with the byte offset).
nlohmann::json parse_json_text(const std::string& text, const std::string& origin);

// For a --set value, where text that is not JSON is a bare string: nullopt when
// `text` is not JSON, the value when it is, InputError when it is JSON but
// breaks one of the rules above (too deep, duplicate keys).
std::optional<nlohmann::json> parse_json_value_or_word(const std::string& text,
                                                       const std::string& origin,
                                                       const std::string& pointer);

// Reads and parses a JSON file (parse_json_text); a missing or unreadable file
// is an InputError naming it.
nlohmann::json read_json_file(const std::string& path);

// True when `text` is well-formed UTF-8.
bool is_utf8(std::string_view text);

}  // namespace penumbra
