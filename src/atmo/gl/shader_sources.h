// GLSL source for the GL backend, assembled from the shared GLSL/C++ common subset (private).
//
// The files of src/atmo/shared are embedded at build time (cmake/EmbedGlsl.cmake), so a shader
// runs exactly the text that the CPU includes as C++ (docs/design.md §1). A GLSL prelude gives the
// subset's names their GLSL meaning, as glsl_cpp.h does for C++: Number is float, IN/OUT/INOUT
// are parameter qualifiers, and the table types are sampler2D.
//
// To use it: BuildComputeShaderSource({"definitions.glsl", "geometry.glsl", ...}, main_source)
// gives a complete compute shader; list the shared files in dependency order (that of shared.h).
#pragma once

#include <initializer_list>
#include <span>
#include <string>
#include <string_view>

namespace atmo::gl {

namespace detail {
struct EmbeddedGlslFile {
  const char* name;    // file name in src/atmo/shared, e.g. "transmittance.glsl"
  const char* source;  // its text, verbatim
};
extern const EmbeddedGlslFile kEmbeddedGlslFiles[];  // generated (embedded_glsl.cc)
extern const int kEmbeddedGlslFileCount;
}  // namespace detail

// The text of an embedded shared file; throws atmo::Error for a file that is not embedded.
std::string_view SharedGlslSource(std::string_view file_name);

// The GLSL prelude: `#version 430 core` and the subset's definitions for GLSL.
std::string_view GlslPrelude();

// prelude + the shared files in the given order + `main_source` (which declares the work-group
// size, the images and uniforms, and main()). Each part starts with `#line 1 N`, N = its index
// (0 prelude, 1.. the files, last the main source), so that compiler messages name the part;
// DescribeSourceStrings() spells the numbering out for error messages.
std::string BuildComputeShaderSource(std::span<const std::string_view> shared_files, std::string_view main_source);
std::string DescribeSourceStrings(std::span<const std::string_view> shared_files);
inline std::string BuildComputeShaderSource(std::initializer_list<std::string_view> shared_files,
                                            std::string_view main_source) {
  return BuildComputeShaderSource(std::span<const std::string_view>(shared_files.begin(), shared_files.size()),
                                  main_source);
}

}  // namespace atmo::gl
