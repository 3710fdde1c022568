// Text from an input, made fit to quote in a one-line message (atmo::Error, warnings): control
// characters become escapes (\n, \r, \t, \xNN). A JSON key or name can hold any of them ("\n" in
// a key of a config was a line break in "unknown key '...'", found by fuzz_json_parameters).
#pragma once

#include <string>
#include <string_view>

namespace atmo {

inline std::string Printable(std::string_view text) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '\n') out += "\\n";
    else if (c == '\r') out += "\\r";
    else if (c == '\t') out += "\\t";
    else if (u < 0x20 || u == 0x7f) out += std::string("\\x") + kHex[u >> 4] + kHex[u & 15];
    else out += c;
  }
  return out;
}

}  // namespace atmo
