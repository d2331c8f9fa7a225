// Names that become folder and file names: a study's name (results/NAME),
// a render's label (images/LABEL.png).
#pragma once

#include <algorithm>
#include <cctype>
#include <string>

namespace penumbra {

inline bool plain_char(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.';
}

// 1 to 100 plain characters, not starting with '.'.
inline bool plain_name(const std::string& name) {
  if (name.empty() || name.size() > 100 || name[0] == '.') return false;
  return std::all_of(name.begin(), name.end(), plain_char);
}

// Labels carry method parameters ("shading-offset(s=0.3)"): keep file names plain.
inline std::string file_safe(const std::string& label) {
  std::string out;
  for (char c : label) out += plain_char(c) ? c : '_';
  return out;
}

// "/height/amplitude" -> "height_amplitude" (separator '_'): ASCII letters
// lower-cased and digits kept, every other run of characters one separator,
// none at either end.
inline std::string lower_words(const std::string& text, char separator) {
  std::string out;
  for (char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if (c < 128 && std::isalnum(c))
      out += static_cast<char>(std::tolower(c));
    else if (!out.empty() && out.back() != separator)
      out += separator;
  }
  while (!out.empty() && out.back() == separator) out.pop_back();
  return out;
}

}  // namespace penumbra
