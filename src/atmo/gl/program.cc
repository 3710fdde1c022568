#include "gl/program.h"

#include <string>
#include <vector>

#include <epoxy/gl.h>

#include "atmo/error.h"

namespace atmo::gl {
namespace {

std::string InfoLog(GLuint object, bool is_program) {
  GLint length = 0;
  if (is_program) {
    glGetProgramiv(object, GL_INFO_LOG_LENGTH, &length);
  } else {
    glGetShaderiv(object, GL_INFO_LOG_LENGTH, &length);
  }
  std::string log(static_cast<std::size_t>(length > 0 ? length : 1), '\0');
  if (is_program) {
    glGetProgramInfoLog(object, length, nullptr, log.data());
  } else {
    glGetShaderInfoLog(object, length, nullptr, log.data());
  }
  log.resize(log.find('\0') == std::string::npos ? log.size() : log.find('\0'));
  return log;
}

}  // namespace

ComputeProgram::ComputeProgram(const std::string& source, std::string_view name, std::string_view source_strings) {
  const GLuint shader = glCreateShader(GL_COMPUTE_SHADER);
  const char* text = source.c_str();
  glShaderSource(shader, 1, &text, nullptr);
  glCompileShader(shader);
  GLint ok = GL_FALSE;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (ok != GL_TRUE) {
    const std::string log = InfoLog(shader, false);
    glDeleteShader(shader);
    throw Error("GL " + std::string(name) + " shader does not compile (" + std::string(source_strings) + "): " + log);
  }
  program_ = glCreateProgram();
  glAttachShader(program_, shader);
  glLinkProgram(program_);
  glDeleteShader(shader);  // deleted with the program
  glGetProgramiv(program_, GL_LINK_STATUS, &ok);
  if (ok != GL_TRUE) {
    const std::string log = InfoLog(program_, true);
    glDeleteProgram(program_);
    throw Error("GL " + std::string(name) + " program does not link: " + log);
  }
}

ComputeProgram::ComputeProgram(const std::string& vertex_source, const std::string& fragment_source,
                               std::string_view name, std::string_view source_strings) {
  GLuint shaders[2] = {glCreateShader(GL_VERTEX_SHADER), glCreateShader(GL_FRAGMENT_SHADER)};
  const std::string* sources[2] = {&vertex_source, &fragment_source};
  for (int i = 0; i < 2; ++i) {
    const char* text = sources[i]->c_str();
    glShaderSource(shaders[i], 1, &text, nullptr);
    glCompileShader(shaders[i]);
    GLint ok = GL_FALSE;
    glGetShaderiv(shaders[i], GL_COMPILE_STATUS, &ok);
    if (ok != GL_TRUE) {
      const std::string log = InfoLog(shaders[i], false);
      glDeleteShader(shaders[0]);
      glDeleteShader(shaders[1]);
      throw Error("GL " + std::string(name) + (i == 0 ? " vertex" : " fragment") + " shader does not compile (" +
                  std::string(source_strings) + "): " + log);
    }
  }
  program_ = glCreateProgram();
  glAttachShader(program_, shaders[0]);
  glAttachShader(program_, shaders[1]);
  glLinkProgram(program_);
  glDeleteShader(shaders[0]);  // deleted with the program
  glDeleteShader(shaders[1]);
  GLint ok = GL_FALSE;
  glGetProgramiv(program_, GL_LINK_STATUS, &ok);
  if (ok != GL_TRUE) {
    const std::string log = InfoLog(program_, true);
    glDeleteProgram(program_);
    throw Error("GL " + std::string(name) + " program does not link: " + log);
  }
}

ComputeProgram::~ComputeProgram() { glDeleteProgram(program_); }

void ComputeProgram::Use() const { glUseProgram(program_); }

void ComputeProgram::SetInt(const std::string& name, int value) const {
  glProgramUniform1i(program_, glGetUniformLocation(program_, name.c_str()), value);
}

void ComputeProgram::SetFloat(const std::string& name, double value) const {
  glProgramUniform1f(program_, glGetUniformLocation(program_, name.c_str()), static_cast<float>(value));
}

void ComputeProgram::SetVec3(const std::string& name, const shared::vec3& value) const {
  glProgramUniform3f(program_, glGetUniformLocation(program_, name.c_str()), static_cast<float>(value.x),
                     static_cast<float>(value.y), static_cast<float>(value.z));
}

void ComputeProgram::SetVec4Array(const std::string& name, const shared::vec4* values, int count) const {
  std::vector<float> data(static_cast<std::size_t>(count) * 4);
  for (int i = 0; i < count; ++i) {
    for (int k = 0; k < 4; ++k) data[static_cast<std::size_t>(i) * 4 + k] = static_cast<float>(values[i][k]);
  }
  glProgramUniform4fv(program_, glGetUniformLocation(program_, name.c_str()), count, data.data());
}

namespace {

void SetDensityProfile(const ComputeProgram& program, const std::string& name, const shared::DensityProfile& profile) {
  for (int i = 0; i < 2; ++i) {
    const std::string layer = name + ".layers[" + std::to_string(i) + "].";
    const shared::DensityProfileLayer& l = profile.layers[i];
    program.SetFloat(layer + "width", l.width);
    program.SetFloat(layer + "exp_term", l.exp_term);
    program.SetFloat(layer + "exp_scale", l.exp_scale);
    program.SetFloat(layer + "linear_term", l.linear_term);
    program.SetFloat(layer + "constant_term", l.constant_term);
  }
}

}  // namespace

// Every member of the struct in definitions.glsl, in its order.
void SetAtmosphereUniforms(const ComputeProgram& program, const std::string& name,
                           const shared::AtmosphereParameters& a) {
  const std::string p = name + ".";
  program.SetFloat(p + "bottom_radius", a.bottom_radius);
  program.SetFloat(p + "top_radius", a.top_radius);
  SetDensityProfile(program, p + "rayleigh_density", a.rayleigh_density);
  program.SetVec3(p + "rayleigh_scattering", a.rayleigh_scattering);
  program.SetVec3(p + "rayleigh_extinction", a.rayleigh_extinction);
  program.SetInt(p + "rayleigh_phase", a.rayleigh_phase);
  SetDensityProfile(program, p + "mie_density", a.mie_density);
  program.SetVec3(p + "mie_scattering", a.mie_scattering);
  program.SetVec3(p + "mie_extinction", a.mie_extinction);
  program.SetInt(p + "mie_phase", a.mie_phase);
  program.SetFloat(p + "mie_g", a.mie_g);
  if (a.mie_phase == shared::kPhaseTabulated) {
    program.SetVec4Array(p + "mie_phase_table[0]", a.mie_phase_table, shared::kPhaseTableSize / 4);
  }
  program.SetFloat(p + "mie_phase_peak_cap", a.mie_phase_peak_cap);
  program.SetFloat(p + "mie_phase_peak_mass", a.mie_phase_peak_mass);
  SetDensityProfile(program, p + "absorption_density", a.absorption_density);
  program.SetVec3(p + "absorption_extinction", a.absorption_extinction);
  program.SetVec3(p + "water_vapor_extinction", a.water_vapor_extinction);
  program.SetVec3(p + "ground_albedo", a.ground_albedo);
  program.SetFloat(p + "sun_angular_radius", a.sun_angular_radius);
  program.SetVec3(p + "wavelength", a.wavelength);
  program.SetInt(p + "sun_limb_darkening", a.sun_limb_darkening);
  program.SetVec3(p + "sun_centre_radiance", a.sun_centre_radiance);
  program.SetInt(p + "density_table_enabled", a.density_table_enabled);
  program.SetFloat(p + "density_table_top", a.density_table_top);
  if (a.density_table_enabled) {
    program.SetVec4Array(p + "density_table[0]", a.density_table, shared::kDensityTableSize);
  }
}

// Every member of CameraParameters in definitions.glsl, in its order.
void SetCameraUniforms(const ComputeProgram& program, const std::string& name, const shared::CameraParameters& c) {
  const std::string p = name + ".";
  program.SetInt(p + "kind", c.kind);
  program.SetInt(p + "width", c.width);
  program.SetInt(p + "height", c.height);
  program.SetFloat(p + "horizontal_fov", c.horizontal_fov);
  program.SetFloat(p + "yaw", c.yaw);
  program.SetFloat(p + "pitch", c.pitch);
  program.SetVec3(p + "forward", c.forward);
  program.SetVec3(p + "right", c.right);
  program.SetVec3(p + "up", c.up);
  program.SetFloat(p + "tan_half_fov", c.tan_half_fov);
}

}  // namespace atmo::gl
