// A name read from a file, as an error message quotes it: control bytes (a newline would break
// the message's one line) as \xNN, the rest (UTF-8 included) as it is.
#pragma once

#include <string>

namespace afterglow::runtime {

inline std::string printableName(const std::string& name) {
  static const char kHex[] = "0123456789abcdef";
  std::string out;
  for (unsigned char c : name) {
    if (c >= 0x20 && c != 0x7f) {
      out += char(c);
    } else {
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
  }
  return out;
}

}  // namespace afterglow::runtime
