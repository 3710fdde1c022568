// One-line messages about files, shared by the image writers (image_io.cc) and the file helpers
// (files.cc).
#pragma once

#include <algorithm>
#include <filesystem>
#include <string>

namespace atmo {

// Our messages are one line; user input and library messages (Iex in particular) may hold newlines.
inline std::string OneLine(std::string text) {
  std::replace(text.begin(), text.end(), '\n', ' ');
  std::replace(text.begin(), text.end(), '\r', ' ');
  return text;
}

// A library's reason, on one line without trailing blanks.
inline std::string Reason(const std::string& text) {
  std::string line = OneLine(text);
  while (!line.empty() && line.back() == ' ') line.pop_back();
  return line;
}

inline std::string WriteError(const std::filesystem::path& path, const std::string& reason) {
  return "cannot write '" + OneLine(path.string()) + "': " + Reason(reason);
}

inline std::string ReadError(const std::filesystem::path& path, const std::string& reason) {
  return "cannot read '" + OneLine(path.string()) + "': " + Reason(reason);
}

}  // namespace atmo
