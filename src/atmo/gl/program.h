// A compiled and linked compute shader program, and the upload of the shared host/GPU structs
// (private to the GL backend).
//
// To use it: `ComputeProgram program(source, "transmittance table");` (throws atmo::Error with the
// compiler's log), then program.Use(), set uniforms, dispatch. Needs a current gl::Context.
#pragma once

#include <string>
#include <string_view>

#include "shared/shared.h"

namespace atmo::gl {

class ComputeProgram {
 public:
  // `name` names the pass in error messages; `source_strings` describes the #line numbering.
  ComputeProgram(const std::string& source, std::string_view name, std::string_view source_strings = "");
  // A vertex + fragment program with the same uniform setters (atmo-viewer's display pass, which
  // runs a frame pass's per-pixel code in its fragment shader: HillaireGl::SetFrameUniforms).
  ComputeProgram(const std::string& vertex_source, const std::string& fragment_source, std::string_view name,
                 std::string_view source_strings);
  ~ComputeProgram();
  ComputeProgram(const ComputeProgram&) = delete;
  ComputeProgram& operator=(const ComputeProgram&) = delete;

  void Use() const;
  unsigned id() const { return program_; }

  // Uniform setters by name; a name that the linker optimised away (location -1) is ignored,
  // as GL itself does.
  void SetInt(const std::string& name, int value) const;
  void SetFloat(const std::string& name, double value) const;
  void SetVec3(const std::string& name, const shared::vec3& value) const;
  // A uniform array of vec4 from its first element's name ("atmosphere.density_table[0]").
  void SetVec4Array(const std::string& name, const shared::vec4* values, int count) const;

 private:
  unsigned program_ = 0;
};

// Uploads a shared::AtmosphereParameters to the uniform struct `name` (e.g. "atmosphere"), member
// by member ("atmosphere.bottom_radius", "atmosphere.rayleigh_density.layers[0].exp_scale", ...),
// converting double to float. The parameters should be in km (ToSharedParameters(p, b, 1000)), so
// that float keeps the radii (~6400 km) to ~0.5 m and the coefficients (~1e-2 per km) are normal.
void SetAtmosphereUniforms(const ComputeProgram& program, const std::string& name,
                           const shared::AtmosphereParameters& atmosphere);

// Uploads a shared::CameraParameters to the uniform struct `name` (e.g. "camera"), member by member.
void SetCameraUniforms(const ComputeProgram& program, const std::string& name, const shared::CameraParameters& camera);

}  // namespace atmo::gl
