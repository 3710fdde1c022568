// atmo-viewer's window, frame loop and panels (viewer.h).
#include "viewer.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <fstream>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <string>
#include <thread>
#include <vector>
// epoxy's gl.h first: GLFW must not include the system GL header.
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>

#include "atmo/colour.h"
#include "atmo/error.h"
#include "atmo/image.h"
#include "atmo/moon.h"
#include "atmo/night_sky.h"
#include "atmo/parameters.h"
#include "atmo/spectrum.h"
#include "cpu/camera.h"
#include "gl/context.h"
#include "gl/exposure_gl.h"
#include "gl/hillaire_gl.h"
#include "gl/night_gl.h"
#include "gl/program.h"
#include "gl/resources.h"
#include "gl/shader_sources.h"
#include "models/reference_model.h"
#include "skies.h"
#include "physics/shared_parameters.h"
#include "script.h"

namespace atmo::viewer {

namespace {

// The most batches of three channels the display pass reads (24 channels): earth-spectral's 15
// and --spectral up to 24 show; more are refused with a message.
constexpr int kMaxDisplayBatches = 8;
// The altitude slider's range, metres: the ground to 1000 km (issue's "orbit"); the command line
// and scripts may go higher.
constexpr float kMaxSliderAltitude_m = 1e6f;
// The luminance false colour's scale: log10 of the luminance (cd/m^2, or the relative unit's) at
// its ends: 0.1 to 10^5 cd/m^2, a night-lit horizon to a hazy sky beside the sun.
constexpr float kLogLuminanceRange[2] = {-1.0f, 5.0f};

// The display's colour scales on the host, for the colour bar (the shader's Diverging and
// Sequential).
ImU32 DivergingColour(float t) {
  const glm::vec3 end = t < 0.0f ? glm::vec3(0.05f, 0.25f, 0.85f) : glm::vec3(0.85f, 0.05f, 0.05f);
  const glm::vec3 c = glm::mix(glm::vec3(1.0f), end, std::abs(t));
  return IM_COL32(static_cast<int>(255 * c.x), static_cast<int>(255 * c.y), static_cast<int>(255 * c.z), 255);
}
ImU32 SequentialColour(float t) {
  const glm::vec3 stops[5] = {{0.05f, 0.0f, 0.3f}, {0.0f, 0.4f, 1.0f}, {0.0f, 0.8f, 0.3f}, {1.0f, 0.9f, 0.0f},
                              {1.0f, 1.0f, 1.0f}};
  const float x = std::clamp(t, 0.0f, 1.0f) * 4.0f;
  const int i = std::min(static_cast<int>(x), 3);
  const glm::vec3 c = glm::mix(stops[i], stops[i + 1], x - static_cast<float>(i));
  return IM_COL32(static_cast<int>(255 * c.x), static_cast<int>(255 * c.y), static_cast<int>(255 * c.z), 255);
}

// Full-screen triangle; the fragment shader reads the frame texel of its pixel (row 0 at the top).
constexpr const char* kDisplayVertexShader = R"glsl(#version 450 core
void main() {
  vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
  gl_Position = vec4(2.0 * p - 1.0, 0.0, 1.0);
}
)glsl";

// The model's channels to linear sRGB (one 3x3 matrix per batch of three channels: the weights of
// atmo::ColourWeights, or the legacy channels times solar_irradiance), exposure, the tone curve on
// luminance or per channel, and the display transfer: ToneMapPixel of src/atmo/io/display.cc in
// float, without the PNG's dither. BATCH_COUNT, TONE_OP (atmo::ToneMapper's order: exp, aces,
// none), PER_CHANNEL, VIEW (0 one sky, 1 split, 2 difference) and FALSE_COLOUR are compiled in
// (DisplayPass keeps one program per choice): llvmpipe ran the uniform branches on them at about
// twice the cost of the whole pass without them. SkyA and SkyB (the compared sky) are written
// out per batch by DisplayPass (SKY_A_SUM, SKY_B_SUM).
constexpr const char* kDisplayFragmentShader = R"glsl(
layout(binding = 0) uniform sampler2D frame0;
layout(binding = 1) uniform sampler2D frame1;
layout(binding = 2) uniform sampler2D frame2;
layout(binding = 3) uniform sampler2D frame3;
layout(binding = 4) uniform sampler2D frame4;
layout(binding = 5) uniform sampler2D frame5;
layout(binding = 6) uniform sampler2D frame6;
layout(binding = 7) uniform sampler2D frame7;
layout(binding = 9) uniform sampler2D compare0;
layout(binding = 10) uniform sampler2D compare1;
layout(binding = 11) uniform sampler2D compare2;
layout(binding = 12) uniform sampler2D compare3;
layout(binding = 13) uniform sampler2D compare4;
layout(binding = 14) uniform sampler2D compare5;
layout(binding = 15) uniform sampler2D compare6;
layout(binding = 16) uniform sampler2D compare7;
// EncodeDisplay(u^2) at u = (i + 0.5) / size: the display transfer as a table, read at sqrt(v),
// where the sRGB curve is nearly linear.
layout(binding = 8) uniform sampler1D encode_table;
uniform mat3 weights[8];
uniform float exposure;
uniform ivec2 frame_size;    // the frame textures' size (reference's is smaller than the window)
uniform ivec2 compare_size;  // the compared sky's
uniform ivec2 window_size;
uniform int split_column;    // split: columns left of it show the sky, the others the compared one
uniform bool split_line;     // a white line at the split (off for --no-panels)
uniform vec2 log_luminance_range;  // false colour: log10 of the luminance at the scale's ends
out vec4 colour;

float Curve(float v) {
#if TONE_OP == 0
  float t = 1.0 - exp(-v);
#elif TONE_OP == 1
  float t = (v * (2.51 * v + 0.03)) / (v * (2.43 * v + 0.59) + 0.14);
#else
  float t = v;
#endif
  return clamp(t, 0.0, 1.0);
}
float Encode(float v) { return texture(encode_table, sqrt(clamp(v, 0.0, 1.0))).r; }
// AgX as AgxDisplay of src/atmo/io/display.cc (its numbers and sources are there): AgxEncoded is
// its 2.2-encoded display value, Agx that value decoded to linear for Encode.
// The sigmoid's two sides differ in constants only: chosen by the sign of d, so that a GPU (or
// SwiftShader, four pixels at a time) evaluates two pows per channel, not both sides' four.
float AgxSigmoid(float x) {
  float d = x - 20.0 / 33.0;
  bool low = d <= 0.0;
  float s = pow(1.0 + (low ? 59.507875 : 69.86278913545539) * pow(abs(d), low ? 3.0 : 3.25),
                low ? -1.0 / 3.0 : -4.0 / 13.0);
  return 0.5 + 2.0 * d * s;
}
vec3 AgxEncoded(vec3 v) {
  // Columns of the inset matrix (rows of display.cc's kAgxInset, transposed).
  const mat3 inset = mat3(0.8424010709504686, 0.04240107095046854, 0.04240107095046854,
                          0.07843650156180276, 0.8784365015618028, 0.07843650156180276,
                          0.0791624274877287, 0.0791624274877287, 0.8791624274877287);
  const float min_ev = -12.473931188332413, max_ev = 4.026068811667588;
  vec3 stops = clamp(log2(max(inset * v, vec3(1e-30))), min_ev, max_ev);
  vec3 x = (stops - min_ev) / (max_ev - min_ev);
  vec3 f = clamp(vec3(AgxSigmoid(x.r), AgxSigmoid(x.g), AgxSigmoid(x.b)), 0.0, 1.0);
  // The outset, inverse(inset), as constants: no 3x3 inverse per pixel (this function is also the
  // web page's display transform, web/CMakeLists.txt).
  const mat3 outset = mat3(1.1969986613119143, -0.053001338688085674, -0.05300133868808568,
                           -0.09804562695225347, 1.1519543730477466, -0.09804562695225344,
                           -0.09895303435966087, -0.09895303435966087, 1.151046965640339);
  return clamp(outset * f, 0.0, 1.0);
}
vec3 Agx(vec3 v) {
  return pow(AgxEncoded(v), vec3(2.2));
}
// The frame's texel under the pixel (the identity where the sizes are equal), row 0 at the top.
ivec2 Texel(ivec2 size) {
  ivec2 texel = ivec2(gl_FragCoord.xy * vec2(size) / vec2(window_size));
  return ivec2(min(texel.x, size.x - 1), size.y - 1 - min(texel.y, size.y - 1));
}
vec3 SkyA(ivec2 texel) {
  vec3 rgb = vec3(0.0);
  SKY_A_SUM
  return rgb;
}
vec3 SkyB(ivec2 texel) {
  vec3 rgb = vec3(0.0);
  SKY_B_SUM
  return rgb;
}
float Luminance(vec3 rgb) { return dot(rgb, vec3(0.2126, 0.7152, 0.0722)); }
vec3 ToneMap(vec3 rgb) {
  vec3 v = max(rgb, vec3(0.0)) * exposure;
#if TONE_OP == 3
  v = Agx(v);
#elif PER_CHANNEL
  v = vec3(Curve(v.r), Curve(v.g), Curve(v.b));
#else
  float y = Luminance(v);
  v = y > 0.0 ? v * (Curve(y) / y) : vec3(0.0);
  float largest = max(v.r, max(v.g, v.b));
  if (largest > 1.0) v /= largest;
#endif
  return vec3(Encode(v.r), Encode(v.g), Encode(v.b));
}
)glsl"
    // The colour scales, the same as the colour bar's (DivergingColour, SequentialColour).
    R"glsl(
vec3 Diverging(float t) {  // t in [-1, 1]: blue, white at 0, red
  return t < 0.0 ? mix(vec3(1.0), vec3(0.05, 0.25, 0.85), -t) : mix(vec3(1.0), vec3(0.85, 0.05, 0.05), t);
}
vec3 Sequential(float t) {  // t in [0, 1]: dark blue, blue, green, yellow, white
  const vec3 stops[5] = vec3[5](vec3(0.05, 0.0, 0.3), vec3(0.0, 0.4, 1.0), vec3(0.0, 0.8, 0.3),
                                vec3(1.0, 0.9, 0.0), vec3(1.0, 1.0, 1.0));
  float x = clamp(t, 0.0, 1.0) * 4.0;
  int i = min(int(x), 3);
  return mix(stops[i], stops[i + 1], x - float(i));
}
// (B - A) / A on a log-symmetric scale: 0 below 0.1 %, +-1/3 at 1 %, +-2/3 at 10 %, +-1 from 100 %.
float DifferenceCoordinate(float a, float b) {
  if (a <= 0.0) return b <= 0.0 ? 0.0 : 1.0;
  float d = (b - a) / a;
  if (abs(d) < 1e-3) return 0.0;
  return sign(d) * clamp((log(abs(d)) / log(10.0) + 3.0) / 3.0, 0.0, 1.0);
}
)glsl";

constexpr const char* kDisplayMain = R"glsl(
void main() {
  ivec2 texel = Texel(frame_size);
#if VIEW == 2
  colour = vec4(Diverging(DifferenceCoordinate(Luminance(SkyA(texel)), Luminance(SkyB(Texel(compare_size))))), 1.0);
  return;
#else
#if VIEW == 1
  int x = int(gl_FragCoord.x);
  if (split_line && x == split_column) {
    colour = vec4(1.0);
    return;
  }
  vec3 rgb = x < split_column ? SkyA(texel) : SkyB(Texel(compare_size));
#else
  vec3 rgb = SkyA(texel);
#endif
#if FALSE_COLOUR
  float y = Luminance(max(rgb, vec3(0.0)));
  float t = (log(max(y, 1e-30)) / log(10.0) - log_luminance_range.x) / (log_luminance_range.y - log_luminance_range.x);
  colour = vec4(Sequential(t), 1.0);
#else
  colour = vec4(ToneMap(rgb), 1.0);
#endif
#endif
}
)glsl";

// The fused pass (DisplayPass::DrawFused): hillaire's frame pass per pixel in the fragment shader
// (gl::HillaireGl::FrameFunctionSource's GetFrameTexel at the pixel's centre, row 0 at the top, as
// the frame pass's invocation of the same pixel computes it), then the display's tone mapping of
// one batch: the frame texture is neither written nor read.
constexpr const char* kFusedMain = R"glsl(
void main() {
  vec2 frag_coord = vec2(gl_FragCoord.x, float(window_size.y) - gl_FragCoord.y);
  vec3 rgb = vec3(0.0);
  rgb += weights[0] * GetFrameTexel(frag_coord).rgb;
  colour = vec4(ToneMap(rgb), 1.0);
}
)glsl";

unsigned CompileShader(GLenum kind, const char* source) {
  const GLuint shader = glCreateShader(kind);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (ok != GL_TRUE) {
    char log[2048] = {};
    glGetShaderInfoLog(shader, sizeof log, nullptr, log);
    throw Error(std::string("display shader: ") + log);
  }
  return shader;
}

// The display pass: one program and an empty vertex array (core profile needs one bound).
class DisplayPass {
 public:
  DisplayPass() {
    glCreateVertexArrays(1, &vao_);
    glCreateTextures(GL_TEXTURE_1D, 1, &encode_table_);
    glTextureStorage1D(encode_table_, 1, GL_R32F, kEncodeTableSize);
    glTextureParameteri(encode_table_, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(encode_table_, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(encode_table_, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  }
  ~DisplayPass() {
    glDeleteTextures(1, &encode_table_);
    glDeleteVertexArrays(1, &vao_);
    for (const auto& [key, program] : programs_) glDeleteProgram(program);
  }
  DisplayPass(const DisplayPass&) = delete;
  DisplayPass& operator=(const DisplayPass&) = delete;

  // What the window shows: one sky, or two (split or difference); false colour of luminance.
  struct View {
    int mode = 0;  // 0 one sky, 1 split, 2 difference
    bool false_colour = false;
    int split_column = 0;
    bool split_line = false;
  };

  // Hillaire's frame and the tone mapping in one pass, straight into the window (one batch of
  // three channels, one sky, no false colour): the pixels of RenderFrame then Draw, without the
  // frame texture's write and read (the display pass costs about a third of the frame pass on
  // llvmpipe, docs/performance.md).
  void DrawFused(const gl::HillaireGl& sky, const shared::CameraParameters& camera, const RadianceTerms& terms,
                 const std::vector<glm::mat3>& weights, const ToneMapping& mapping, int width, int height) const {
    glViewport(0, 0, width, height);
    const gl::ComputeProgram& program =
        FusedProgram(sky, static_cast<int>(mapping.op), mapping.per_channel, sky.uses_sky_view());
    sky.SetFrameUniforms(program, camera, terms, 0);
    program.Use();
    const GLuint id = program.id();
    glUniformMatrix3fv(glGetUniformLocation(id, "weights"), 1, GL_FALSE, &weights[0][0][0]);
    glUniform1f(glGetUniformLocation(id, "exposure"), static_cast<float>(mapping.exposure));
    if (mapping.transfer != encoded_transfer_ || mapping.gamma != encoded_gamma_) FillEncodeTable(mapping);
    glBindTextureUnit(8, encode_table_);
    glUniform2i(glGetUniformLocation(id, "window_size"), width, height);
    glBindVertexArray(vao_);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
    glUseProgram(0);
  }

  void Draw(const Sky& sky, const Sky* compared, const View& view, const std::vector<glm::mat3>& weights,
            const ToneMapping& mapping, int width, int height) const {
    glViewport(0, 0, width, height);
    const int batches = static_cast<int>(sky.batch_count());
    const int mode = compared != nullptr ? view.mode : 0;
    const GLuint program =
        Program(batches, static_cast<int>(mapping.op), mapping.per_channel, mode, view.false_colour && mode != 2);
    glUseProgram(program);
    for (int b = 0; b < batches; ++b) glBindTextureUnit(b, sky.frame_texture(b).id());
    if (mode != 0) {
      for (int b = 0; b < batches; ++b) glBindTextureUnit(9 + b, compared->frame_texture(b).id());
      const shared::ivec2 size = compared->frame_texture(0).size2();
      glUniform2i(glGetUniformLocation(program, "compare_size"), size.x, size.y);
      glUniform1i(glGetUniformLocation(program, "split_column"), view.split_column);
      glUniform1i(glGetUniformLocation(program, "split_line"), view.split_line ? 1 : 0);
    }
    glUniformMatrix3fv(glGetUniformLocation(program, "weights"), batches, GL_FALSE, &weights[0][0][0]);
    glUniform1f(glGetUniformLocation(program, "exposure"), static_cast<float>(mapping.exposure));
    glUniform2f(glGetUniformLocation(program, "log_luminance_range"), kLogLuminanceRange[0], kLogLuminanceRange[1]);
    if (mapping.transfer != encoded_transfer_ || mapping.gamma != encoded_gamma_) FillEncodeTable(mapping);
    glBindTextureUnit(8, encode_table_);
    const shared::ivec2 frame_size = sky.frame_texture(0).size2();
    glUniform2i(glGetUniformLocation(program, "frame_size"), frame_size.x, frame_size.y);
    glUniform2i(glGetUniformLocation(program, "window_size"), width, height);
    glBindVertexArray(vao_);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
    glUseProgram(0);
  }

 private:
  // The fused program for a tone curve and the frame's sky function (sky-view table or march).
  const gl::ComputeProgram& FusedProgram(const gl::HillaireGl& sky, int tone_op, bool per_channel,
                                         bool sky_view) const {
    const int key = (sky_view ? 100 : 0) + tone_op * 10 + (per_channel ? 1 : 0);
    const auto found = fused_programs_.find(key);
    if (found != fused_programs_.end()) return *found->second;
    const std::string main = sky.FrameFunctionSource() + "\n#define TONE_OP " + std::to_string(tone_op) +
                             "\n#define PER_CHANNEL " + std::to_string(per_channel ? 1 : 0) +
                             "\n#define SKY_A_SUM\n#define SKY_B_SUM\n" + kDisplayFragmentShader + kFusedMain;
    const std::span<const std::string_view> files = gl::HillaireGl::FrameSharedFiles();
    auto program = std::make_unique<gl::ComputeProgram>(kDisplayVertexShader,
                                                        gl::BuildComputeShaderSource(files, main), "fused display",
                                                        gl::DescribeSourceStrings(files));
    return *fused_programs_.emplace(key, std::move(program)).first->second;
  }
  // The program for a batch count, tone curve and mode, compiled on first use.
  GLuint Program(int batches, int tone_op, bool per_channel, int mode, bool false_colour) const {
    const int key = batches * 10000 + mode * 1000 + (false_colour ? 100 : 0) + tone_op * 10 + (per_channel ? 1 : 0);
    const auto found = programs_.find(key);
    if (found != programs_.end()) return found->second;
    std::string sum_a;
    std::string sum_b;
    for (int b = 0; b < batches; ++b) {
      const std::string index = std::to_string(b);
      sum_a += "rgb += weights[" + index + "] * texelFetch(frame" + index + ", texel, 0).rgb; ";
      sum_b += "rgb += weights[" + index + "] * texelFetch(compare" + index + ", texel, 0).rgb; ";
    }
    const std::string source = "#version 450 core\n#define BATCH_COUNT " + std::to_string(batches) +
                               "\n#define TONE_OP " + std::to_string(tone_op) + "\n#define PER_CHANNEL " +
                               std::to_string(per_channel ? 1 : 0) + "\n#define VIEW " + std::to_string(mode) +
                               "\n#define FALSE_COLOUR " + std::to_string(false_colour ? 1 : 0) +
                               "\n#define SKY_A_SUM " + sum_a + "\n#define SKY_B_SUM " + sum_b + "\n" +
                               kDisplayFragmentShader + kDisplayMain;
    const GLuint vs = CompileShader(GL_VERTEX_SHADER, kDisplayVertexShader);
    const GLuint fs = CompileShader(GL_FRAGMENT_SHADER, source.c_str());
    const GLuint program = glCreateProgram();
    glAttachShader(program, vs);
    glAttachShader(program, fs);
    glLinkProgram(program);
    glDeleteShader(vs);
    glDeleteShader(fs);
    GLint ok = 0;
    glGetProgramiv(program, GL_LINK_STATUS, &ok);
    if (ok != GL_TRUE) throw Error("display shader: link failed");
    programs_.emplace(key, program);
    return program;
  }
  // 4096 entries: at the dark end u = 1/8192 is v = 1.5e-8, below an 8-bit code; the sRGB curve's
  // largest gap between neighbours is 0.0015, a tenth of an 8-bit code.
  static constexpr int kEncodeTableSize = 4096;
  void FillEncodeTable(const ToneMapping& mapping) const {
    std::vector<float> table(kEncodeTableSize);
    for (int i = 0; i < kEncodeTableSize; ++i) {
      const double u = (i + 0.5) / kEncodeTableSize;
      table[i] = static_cast<float>(EncodeDisplay(u * u, mapping));
    }
    glTextureSubImage1D(encode_table_, 0, 0, kEncodeTableSize, GL_RED, GL_FLOAT, table.data());
    encoded_transfer_ = mapping.transfer;
    encoded_gamma_ = mapping.gamma;
  }

  mutable std::map<int, GLuint> programs_;
  mutable std::map<int, std::unique_ptr<gl::ComputeProgram>> fused_programs_;
  GLuint vao_ = 0;
  GLuint encode_table_ = 0;
  mutable std::optional<DisplayTransfer> encoded_transfer_;
  mutable double encoded_gamma_ = 0.0;
};

// The ViewState knobs of an atmosphere as loaded (multipliers 1, its g, albedo and radius).
void ResetAtmosphereKnobs(const AtmosphereParameters& p, ViewState& state) {
  state.rayleigh_density = 1.0;
  state.mie_density = 1.0;
  state.ozone_density = 1.0;
  state.mie_g = p.mie.phase_g;
  double albedo = 0.0;
  for (const double a : p.ground_albedo) albedo += a;
  state.ground_albedo = p.ground_albedo.empty() ? 0.0 : albedo / static_cast<double>(p.ground_albedo.size());
  state.ground_radius_m = p.ground_radius_m;
}

// The loaded atmosphere with the knobs applied; a knob at its loaded value leaves the parameter
// as it is, bit for bit (so that a screenshot matches `atmo render` with the same config).
AtmosphereParameters ApplyAtmosphereKnobs(const AtmosphereParameters& base, const ViewState& loaded,
                                          const ViewState& state) {
  AtmosphereParameters p = base;
  const auto scale = [](Medium& medium, double factor) {
    if (factor == 1.0) return;
    for (double& s : medium.scattering_per_m) s *= factor;
    for (double& a : medium.absorption_per_m) a *= factor;
  };
  scale(p.rayleigh, state.rayleigh_density);
  scale(p.mie, state.mie_density);
  scale(p.ozone, state.ozone_density);
  if (state.mie_g != loaded.mie_g) {
    p.mie.phase_g = state.mie_g;
    // A tabulated phase function has no g to change: the slider gives a Henyey-Greenstein one.
    if (p.mie.phase == PhaseFunction::kTabulated) {
      p.mie.phase = PhaseFunction::kHenyeyGreenstein;
      p.mie.phase_table.clear();
    }
  }
  if (state.ground_albedo != loaded.ground_albedo) p.ground_albedo.assign(p.channel_count(), state.ground_albedo);
  if (state.ground_radius_m != loaded.ground_radius_m) {
    p.top_radius_m = state.ground_radius_m + (base.top_radius_m - base.ground_radius_m);
    p.ground_radius_m = state.ground_radius_m;
  }
  if (!(p == base)) p.name = "custom";
  Validate(p);
  return p;
}

// Moves an altitude smoothly on a log scale through 0: (h + 10 m) grows by e^step.
double StepAltitude(double altitude_m, double step) {
  return std::clamp((altitude_m + 10.0) * std::exp(step) - 10.0, 0.0, static_cast<double>(kMaxSliderAltitude_m));
}

// The back buffer as 8-bit display values (read bottom-up, written top row first), as a PNG of
// those values unchanged (DisplayTransfer::kIdentity, no curve, no dither).
void WriteWindow(const std::string& path, int width, int height, bool offscreen) {
  std::vector<unsigned char> rgb(static_cast<std::size_t>(width) * height * 3);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadBuffer(offscreen ? GL_COLOR_ATTACHMENT0 : GL_BACK);
  glReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, rgb.data());
  Image image(width, height, 3);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      for (int c = 0; c < 3; ++c) {
        image.at(x, y, c) = rgb[(static_cast<std::size_t>(height - 1 - y) * width + x) * 3 + c] / 255.0f;
      }
    }
  }
  ToneMapping identity;
  identity.op = ToneMapper::kNone;
  identity.exposure = 1.0;
  identity.per_channel = true;
  identity.transfer = DisplayTransfer::kIdentity;
  identity.dither = false;
  WritePng(path, image, identity);
  std::printf("atmo-viewer: wrote %s (the window, %dx%d)\n", path.c_str(), width, height);
}

void WriteConfig(const std::string& path, const AtmosphereParameters& parameters) {
  const std::string json = ToJson(parameters);
  WriteFileAtomically(path, [&](const std::filesystem::path& temporary) {
    std::ofstream out(temporary, std::ios::binary);
    out << json << '\n';
    if (!out) throw Error("write failed");
  });
}

// Whether two states have the same atmosphere knobs.
bool SameKnobs(const ViewState& a, const ViewState& b) {
  return a.rayleigh_density == b.rayleigh_density && a.mie_density == b.mie_density &&
         a.ozone_density == b.ozone_density && a.mie_g == b.mie_g && a.ground_albedo == b.ground_albedo &&
         a.ground_radius_m == b.ground_radius_m;
}

void CopyKnobs(const ViewState& from, ViewState& to) {
  to.rayleigh_density = from.rayleigh_density;
  to.mie_density = from.mie_density;
  to.ozone_density = from.ozone_density;
  to.mie_g = from.mie_g;
  to.ground_albedo = from.ground_albedo;
  to.ground_radius_m = from.ground_radius_m;
}

// The options of model source4d (Source4dModelSettings::FromOptions's keys) for `settings`: the
// panel's edits and a screenshot's atmo:modelOptions.
ModelOptions Source4dOptions(const Source4dModelSettings& settings) {
  const cpu::Source4dSettings& t = settings.tables;
  ModelOptions options;
  options["table"] = cli::Format("%dx%dx%dx%d", t.r_size, t.mu_size, t.mu_s_size, t.phi_size);
  options["gather"] = cli::Format("%dx%d", t.gather_zeniths, t.gather_azimuths);
  options["gather_samples"] = std::to_string(t.gather_samples);
  options["orders"] = std::to_string(t.orders);
  options["tail"] = t.tail ? "on" : "off";
  options["samples"] = std::to_string(settings.samples);
  options["transmittance_lut"] = cli::Format("%dx%d", t.transmittance_lut.x, t.transmittance_lut.y);
  options["transmittance_samples"] = std::to_string(t.transmittance_samples);
  return options;
}

// The GPU passes are timed in every 4th frame (1, 5, 9, ...): on llvmpipe the timers' glFinish
// per pass cost 3 % of the benchmark's frame (docs/performance.md). On a GPU the timer queries
// are read when the next timed frame starts (PassTimings::Collect without waiting), so timing
// never stalls the pipeline there.
constexpr int kTimedEvery = 4;

// The window of --offscreen: a headless context draws into an RGBA8 framebuffer of the window's
// size, and Present() stands in for the swap. A swap chain keeps a frame loop at most a few
// frames ahead of the GPU; here a fence per frame does: Present waits for the frame two before
// (kFramesInFlight), so that frame times measure the GPU's throughput, not the submission's.
class OffscreenTarget {
 public:
  OffscreenTarget(int width, int height) : width_(width), height_(height) {
    glCreateRenderbuffers(1, &colour_);
    glNamedRenderbufferStorage(colour_, GL_RGBA8, width, height);
    glCreateFramebuffers(1, &framebuffer_);
    glNamedFramebufferRenderbuffer(framebuffer_, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, colour_);
    if (glCheckNamedFramebufferStatus(framebuffer_, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
      throw Error("atmo-viewer --offscreen: the " + std::to_string(width) + "x" + std::to_string(height) +
                  " framebuffer is incomplete");
    }
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_);
  }
  ~OffscreenTarget() {
    for (GLsync fence : fences_) glDeleteSync(fence);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDeleteFramebuffers(1, &framebuffer_);
    glDeleteRenderbuffers(1, &colour_);
  }
  OffscreenTarget(const OffscreenTarget&) = delete;
  OffscreenTarget& operator=(const OffscreenTarget&) = delete;
  int width() const { return width_; }
  int height() const { return height_; }
  void Present() {
    fences_.push_back(glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0));
    while (fences_.size() > kFramesInFlight) {
      glClientWaitSync(fences_.front(), GL_SYNC_FLUSH_COMMANDS_BIT, GLuint64{60'000'000'000});
      glDeleteSync(fences_.front());
      fences_.pop_front();
    }
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_);  // ImGui's renderer restores it too
  }

 private:
  static constexpr std::size_t kFramesInFlight = 2;
  int width_;
  int height_;
  GLuint colour_ = 0;
  GLuint framebuffer_ = 0;
  std::deque<GLsync> fences_;
};

class Viewer {
 public:
  explicit Viewer(const ViewerOptions& options);
  ~Viewer();
  int Run();

 private:
  // Moves the last timed frame's collected times to the panel and the run's summary and clears
  // timings_ for the next timed frame (waiting for the GPU only when `wait` or when they are
  // still not ready).
  void ReadTimings(bool wait);
  // A new sky of `model` for `parameters` and the settings (tables not computed yet); throws
  // atmo::Error.
  std::unique_ptr<Sky> MakeSky(const std::string& model, const AtmosphereParameters& parameters) const;
  // Builds the sky the state asks for (a model, an atmosphere, settings) as a pending one and
  // shows it once complete; on an error goes back to what is shown.
  void UpdateSky();
  // Whether what is shown is final: no sky pending, and the shown one converged (reference).
  bool Settled() const {
    const bool compare_settled =
        compare_model_.empty() || (compare_pending_ == nullptr && compare_sky_ != nullptr && compare_sky_->Converged());
    return pending_ == nullptr && sky_ != nullptr && sky_->Converged() && compare_settled && waiting_shots_.empty();
  }
  // The compared sky (compare mode): compare_model_ on the shown atmosphere, built as the main one.
  void UpdateCompareSky();
  // A loaded atmosphere (preset or config) as the base: made spectral when state_.spectral.
  void LoadBase(const AtmosphereParameters& parameters) {
    rgb_base_ = parameters;
    base_spectral_ = state_.spectral;
    base_ = base_spectral_ ? MakeSpectral(rgb_base_, spectral_count_) : rgb_base_;
  }
  void DrawColourBar(int mode, bool false_colour);
  void UpdateDisplayWeights();
  void HandleInput(double dt_s);
  void DrawPanels();
  void Screenshot(const std::string& exr_path, const std::string& png_path);
  void FollowDate();  // the sun of --date + date_hours
  cli::RenderPlan CurrentPlan() const;
  // The night sky of the shown view (include/atmo/night_sky.h), rebuilt when the sky, the
  // observer, the sun or the instant changed; null for a half-space. NightShown: whether the
  // frames get it on the GPU now (NightSkyGl).
  void UpdateNight();
  bool NightShown() const;
  bool NightOnGpu(const Sky& sky) const;  // NightShown for `sky` (the shown or the compared one)
  // Hands the night sky and the moon of the view to a sky that draws them itself (Sky::DrawsNight).
  void GiveNight(Sky& sky) const;
  // Adds the night sky to `sky`'s frame textures, just rendered through `camera`.
  void AddNight(const Sky& sky, const Camera& camera);
  // The moon's light: RenderMoonlit renders `sky` for a sun in the moon's direction (no disc) into
  // `moon_frames` and puts the sky's view back to the sun's; AddMoon adds those frames times the
  // moon's relative irradiance and its disc to the frames just rendered.
  void RenderMoonlit(Sky& sky, const Camera& camera, const RadianceTerms& terms,
                     std::vector<gl::GpuTexture>& moon_frames);
  void AddMoon(const Sky& sky, const Camera& camera, const std::vector<gl::GpuTexture>& moon_frames);
  void SetViewToMoon(Sky& sky);

  ViewerOptions options_;
  cli::RenderPlan plan_;               // from the flags, as `atmo render` plans them
  AtmosphereParameters base_;          // the loaded atmosphere (preset or config), before the knobs
  AtmosphereParameters current_;       // with the knobs
  // What the shown tables were made from, to go back to when a change fails.
  AtmosphereParameters current_base_;
  ViewState current_loaded_;
  int current_preset_index_ = -1;
  HillaireSettings shown_settings_;
  bool settings_changed_ = false;  // the panel's hillaire options moved
  HillaireSettings settings_;
  ElekSettings elek_settings_;     // --option of --model elek, else elek's defaults
  Source4dModelSettings source4d_settings_;        // --option of --model source4d, then the panel's
  Source4dModelSettings shown_source4d_settings_;  // of the shown sky (to go back to on an error)
  bool source4d_cpu_tables_ = false;               // --source4d-tables resolved (the panel's choice)
  bool shown_source4d_cpu_tables_ = false;         // of the shown sky
  ModelOptions reference_options_;  // --option and --seed of --model reference
  std::string shown_model_;        // the model of sky_
  ViewState state_;
  ViewState loaded_;  // the knobs of base_
  ViewState built_;   // what the sky view was last made for
  // The frame textures' contents: sky_generation_, camera and terms of the last RenderFrame of
  // the shown sky (drawn_generation_ -1: unknown, e.g. after a screenshot or the fused pass).
  int sky_generation_ = 0;
  int drawn_generation_ = -1;
  // The last frame showed an unchanged frame while the next sky's tables build on a thread of
  // their own: the next frame waits for input up to kBuildWaitS first (Run).
  bool waiting_for_build_ = false;
  Camera drawn_camera_;
  RadianceTerms drawn_terms_;
  bool drawn_night_ = false;  // the night sky is in the frame textures
  ViewState shown_knobs_;  // the atmosphere knobs of what is shown
  std::unique_ptr<gl::Context> context_;
  std::unique_ptr<Sky> sky_;      // shown
  std::unique_ptr<Sky> pending_;  // being built (elek), shown once complete
  std::string pending_model_;
  AtmosphereParameters pending_parameters_;
  HillaireSettings pending_settings_;
  std::FILE* frame_log_ = nullptr;
  // Compare mode: the compared model (empty: none), how it shows (1 split, 2 difference), where
  // the split is (a fraction of the width), luminance in false colour.
  std::string compare_model_;
  int compare_view_ = 1;
  double split_ = 0.5;
  bool false_colour_ = false;
  std::unique_ptr<Sky> compare_sky_;
  std::unique_ptr<Sky> compare_pending_;
  std::string compare_shown_model_;
  std::string compare_pending_model_;
  AtmosphereParameters compare_parameters_;          // of compare_sky_
  AtmosphereParameters compare_pending_parameters_;  // of compare_pending_
  bool compare_view_dirty_ = false;
  // The spectral toggle: base_ is rgb_base_ or MakeSpectral(rgb_base_, spectral_count_)
  // (base_spectral_); spectral_count_ is --spectral's, or 15 (earth-spectral's).
  AtmosphereParameters rgb_base_;
  AtmosphereParameters current_rgb_base_;
  bool base_spectral_ = false;
  bool shown_spectral_ = false;
  int spectral_count_ = 15;
  std::unique_ptr<DisplayPass> display_;
  std::vector<glm::mat3> weights_;
  ViewerScript script_;
  ToneMapping mapping_;
  bool tables_dirty_ = true;
  bool view_dirty_ = true;
  std::string status_;  // the last error or file written, shown in the panel
  // The Files panel's text fields (ImGui edits them in place).
  char config_path_[512] = "viewer_config.json";
  char screenshot_name_[512] = "viewer";
  int preset_index_ = -1;
  PassTimings timings_;        // the last timed frame's passes (GPU time; swap on the host)
  int timings_frame_ = -1;     // the frame timings_ holds (-1: none)
  PassTimings shown_timings_;  // the last timed frame's that is read, for the panel
  PassTimings run_timings_;    // every timed frame's but the first, for the summary of a --frames run
  PassTimings* pass_timings_ = nullptr;  // &timings_ in a timed frame, else null (no GPU waits)
  double frame_ms_ = 0.0;
  double metered_ev100_ = 0.0;
  bool metered_ = false;  // metered_ev100_ is of the shown sky
  std::unique_ptr<gl::ExposureMeter> meter_;  // auto-exposure on the GPU
  // The night sky: the glow and the stars of the shown view (night_), added to every frame the
  // sky renders while the sun is below the horizon (NightShown) by night_gl_, and on the host to
  // screenshots (as `atmo render` adds it). night_key_ is what night_ was made for.
  const StarCatalogue* stars_ = nullptr;  // --star-catalogue or stellarium-data; null: none
  std::shared_ptr<NightSky> night_;
  std::unique_ptr<gl::NightSkyGl> night_gl_;
  std::vector<double> night_key_;
  // The moon of --moon-* or of --date (with the night sky; include/atmo/moon.h), shown with the
  // night sky; its moonlit frames; its disc integrated over the pixels on the host (the patch
  // of the frame that holds it, from moon_disc_origin_), for the camera and moon of moon_disc_key_.
  std::shared_ptr<const Moon> moon_;
  MoonPosition moon_place_;  // of moon_: its elevation and azimuth, the "sun" of its moonlit frames
  std::vector<gl::GpuTexture> moon_frames_;
  std::vector<gl::GpuTexture> compare_moon_frames_;  // the compared sky's (--compare)
  Image moon_disc_;
  shared::ivec2 moon_disc_origin_{0, 0};
  std::vector<double> moon_disc_key_;
  std::unique_ptr<OffscreenTarget> offscreen_;  // --offscreen: the window's stand-in (else null)
  Metering metering_ = Metering::kAdaptive;   // of the last metering queued
  int settings_generation_ = 0;          // counts the panel's hillaire option changes
  int pending_settings_generation_ = 0;  // of pending_
  std::string requested_model_;          // state_.model when UpdateSky last ran
  int frame_ = 0;
  // --date: the sun follows the date plus state_.date_hours, played at play_speed_ hours per
  // second, until the sun is moved by hand (date_follows_ false).
  bool date_follows_ = false;
  bool playing_ = false;
  double play_speed_ = 0.5;
  std::optional<cli::SunAtInstant> dated_sun_;  // the instant the sun shows, when it follows the date
  bool dragging_view_ = false;
  bool dragging_sun_ = false;
  bool dragging_split_ = false;
  std::vector<std::string> waiting_shots_;  // script screenshots waiting for a sky to write
  double last_x_ = 0.0;
  double last_y_ = 0.0;
};

Viewer::Viewer(const ViewerOptions& options) : options_(options) {
  const std::vector<std::string>& models = ViewerModelNames();
  if (std::find(models.begin(), models.end(), options_.common.model) == models.end()) {
    throw Error("atmo-viewer shows models hillaire, elek, simple, reference and source4d (got --model " +
                options_.common.model + ")");
  }
  if (options_.common.backend != "cpu" && options_.common.backend != "gl") {
    throw Error("unknown backend '" + options_.common.backend + "'");
  }
  options_.common.backend = "gl";  // the viewer runs on the GL backend; the metadata says so
  if (options_.render.camera == "cubemap") throw Error("atmo-viewer has no cubemap camera (use atmo render)");
  if (options_.render.spp && options_.common.model != "reference") {
    throw Error("--spp is the path count of model reference; model '" + options_.common.model +
                "' is deterministic and takes no --spp");
  }
  plan_ = cli::PlanRender(options_.common, options_.render);
  base_ = plan_.parameters;
  rgb_base_ = base_;
  if (options_.common.spectral != 0) {
    // The RGB form of --spectral's atmosphere, for the panel's toggle.
    cli::CommonOptions rgb = options_.common;
    rgb.spectral = 0;
    rgb_base_ = cli::PlanRender(rgb, options_.render).parameters;
    spectral_count_ = options_.common.spectral;
    state_.spectral = true;
    base_spectral_ = true;
  }
  current_rgb_base_ = rgb_base_;
  shown_spectral_ = base_spectral_;
  if (static_cast<int>(ChannelBatchCount(base_.channel_count())) > kMaxDisplayBatches) {
    throw Error("atmo-viewer shows up to " + std::to_string(3 * kMaxDisplayBatches) + " channels (got " +
                std::to_string(base_.channel_count()) + "); use fewer --spectral wavelengths");
  }
  // --option configures the model of --model; the others shown from the panel use their defaults.
  const std::string& model = options_.common.model;
  cli::CommonOptions defaults = options_.common;
  defaults.options.clear();
  settings_ = cli::GlHillaireSettings(model == "hillaire" ? options_.common : defaults);
  elek_settings_ = cli::GlElekSettings(model == "elek" ? options_.common : defaults);
  source4d_settings_ = cli::GlSource4dSettings(model == "source4d" ? options_.common : defaults);
  shown_source4d_settings_ = source4d_settings_;
  if (model == "reference") {
    reference_options_ = cli::ParseModelOptions(options_.common.options);
    ReferenceSettings::FromOptions(reference_options_);  // a bad option is refused now
  }
  if (options_.common.seed_given) reference_options_["seed"] = std::to_string(options_.common.seed);
  state_.model = model;
  mapping_ = plan_.mapping;
  const RenderSettings& s = plan_.settings;
  state_.camera = s.camera.kind;
  state_.yaw_deg = s.camera.yaw_deg;
  state_.pitch_deg = s.camera.pitch_deg;
  state_.fov_deg = s.camera.fov_deg;
  state_.altitude_m = s.altitude_m;
  state_.sun_elevation_deg = s.sun_elevation_deg;
  state_.sun_azimuth_deg = s.sun_azimuth_deg;
  state_.sun_disc = s.terms.sun_disc;
  state_.ground = s.terms.ground;
  // The exposure as `atmo render` chooses the PNG's: --exposure, --ev, else metered (auto).
  const bool legacy = plan_.unit == RadianceUnit::kRelative && base_.channel_count() == 3;
  if (options_.render.exposure) {
    state_.auto_exposure = false;
    state_.ev100 = Ev100FromExposure(*options_.render.exposure);
  } else if (options_.render.ev100) {
    state_.auto_exposure = false;
    state_.ev100 = *options_.render.ev100;
  } else if (legacy && !options_.render.auto_exposure) {
    state_.auto_exposure = false;
    state_.ev100 = Ev100FromExposure(base_.exposure);
  } else {
    state_.auto_exposure = true;
  }
  date_follows_ = plan_.dated_sun.has_value();
  dated_sun_ = plan_.dated_sun;
  ResetAtmosphereKnobs(base_, state_);
  loaded_ = state_;
  shown_knobs_ = state_;
  current_ = base_;
  compare_model_ = options_.compare;
  if (!compare_model_.empty() && std::find(models.begin(), models.end(), compare_model_) == models.end()) {
    throw Error("--compare takes hillaire, elek, simple, reference or source4d (got " + compare_model_ + ")");
  }
  if (options_.compare_view != "split" && options_.compare_view != "difference") {
    throw Error("--compare-view takes split or difference (got " + options_.compare_view + ")");
  }
  compare_view_ = options_.compare_view == "split" ? 1 : 2;
  split_ = options_.split;
  if (!options_.false_colour.empty() && options_.false_colour != "luminance") {
    throw Error("--false-colour takes luminance (got " + options_.false_colour + ")");
  }
  false_colour_ = options_.false_colour == "luminance";
  const std::string& tables = options_.common.source4d_tables;
  if (tables != "gpu" && tables != "cpu" && tables != "auto") {
    throw Error("--source4d-tables takes gpu, cpu or auto (got '" + tables + "')");
  }
  if (!options_.frame_log.empty()) {
    cli::CheckOutputWritable(options_.frame_log);
    frame_log_ = std::fopen(options_.frame_log.c_str(), "w");
    if (frame_log_ == nullptr) throw Error("cannot write " + options_.frame_log);
    std::fprintf(frame_log_, "frame ms shown_model pending_model progress\n");
  }
  if (!options_.script_path.empty()) {
    script_ = ParseViewerScript(ReadFileBounded(options_.script_path, "script "), options_.script_path);
  }
  const std::vector<std::string> presets = PresetNames();
  for (std::size_t i = 0; i < presets.size(); ++i) {
    if (presets[i] == base_.name) preset_index_ = static_cast<int>(i);
  }

  if (options_.offscreen) {
    context_ = std::make_unique<gl::Context>();
    offscreen_ = std::make_unique<OffscreenTarget>(options_.render.width, options_.render.height);
  } else {
    gl::WindowOptions window;
    window.width = options_.render.width;
    window.height = options_.render.height;
    window.title = "atmo-viewer";
    window.visible = !options_.hidden;
    context_ = std::make_unique<gl::Context>(window);
  }
  // auto: the CPU on a software rasteriser, where GL passes run on the same cores ~8x slower.
  source4d_cpu_tables_ = tables == "cpu" || (tables == "auto" && context_->software_renderer());
  shown_source4d_cpu_tables_ = source4d_cpu_tables_;
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini beside the user's files
  ImGui::StyleColorsDark();
  if (offscreen_ == nullptr) {
    // Scripted runs measure frames, not the display's refresh: no vsync.
    glfwSwapInterval(options_.frames > 0 ? 0 : 1);
    ImGui_ImplGlfw_InitForOpenGL(static_cast<GLFWwindow*>(context_->window()), true);
  }
  ImGui_ImplOpenGL3_Init("#version 450");
  display_ = std::make_unique<DisplayPass>();
  meter_ = std::make_unique<gl::ExposureMeter>();
  night_gl_ = std::make_unique<gl::NightSkyGl>(*context_);
  stars_ = cli::LoadStarsFor(options_.render, base_);
}

Viewer::~Viewer() {
  if (frame_log_ != nullptr) std::fclose(frame_log_);
  compare_pending_.reset();
  compare_sky_.reset();
  pending_.reset();
  sky_.reset();
  JoinSource4dCpuBuilds();  // of skies destroyed while their tables were built (cancelled)
  display_.reset();
  meter_.reset();
  night_gl_.reset();
  offscreen_.reset();
  ImGui_ImplOpenGL3_Shutdown();
  if (context_->window() != nullptr) ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
}

void Viewer::UpdateDisplayWeights() {
  // Per channel, its linear sRGB weights (atmo::ColourWeights; the legacy 3-channel relative
  // render shows its channels times solar_irradiance, as `atmo render`'s PNG does).
  const std::size_t nc = current_.channel_count();
  std::vector<glm::vec3> per_channel(nc, glm::vec3(0.0f));
  if (plan_.unit == RadianceUnit::kRelative && nc == 3) {
    for (std::size_t c = 0; c < 3; ++c) per_channel[c][c] = 1.0f;  // the frame has solar_irradiance in it
  } else {
    per_channel = ColourWeights(SpectralConversion(current_.wavelengths_nm), ImageColour::kLinearSrgb);
  }
  weights_.assign(kMaxDisplayBatches, glm::mat3(0.0f));
  for (std::size_t c = 0; c < nc; ++c) weights_[c / 3][c % 3] = per_channel[c];
}

std::unique_ptr<Sky> Viewer::MakeSky(const std::string& model, const AtmosphereParameters& parameters) const {
  if (static_cast<int>(ChannelBatchCount(parameters.channel_count())) > kMaxDisplayBatches) {
    throw Error("atmo-viewer shows up to " + std::to_string(3 * kMaxDisplayBatches) + " channels (got " +
                std::to_string(parameters.channel_count()) + ")");
  }
  SkyRequest request;
  request.model = model;
  request.parameters = parameters;
  if (plan_.unit != RadianceUnit::kRelative) {
    request.parameters.solar_irradiance.assign(parameters.channel_count(), 1.0);
  }
  request.hillaire = settings_;
  request.elek = elek_settings_;
  request.source4d = source4d_settings_;
  request.source4d_cpu_tables = source4d_cpu_tables_;
  request.reference_options = reference_options_;
  request.reference_spp = options_.render.spp.value_or(0);
  request.reference_divisor = options_.reference_divisor;
  return viewer::MakeSky(*context_, request);
}

cli::RenderPlan Viewer::CurrentPlan() const {
  cli::RenderPlan plan = plan_;
  plan.parameters = current_;
  plan.model_parameters = current_;
  if (plan.unit != RadianceUnit::kRelative)
    plan.model_parameters.solar_irradiance.assign(current_.channel_count(), 1.0);
  plan.settings.camera = ViewCamera(state_, options_.render.width, options_.render.height);
  plan.settings.altitude_m = state_.altitude_m;
  plan.settings.sun_elevation_deg = state_.sun_elevation_deg;
  plan.settings.sun_azimuth_deg = state_.sun_azimuth_deg;
  plan.settings.terms.sun_disc = state_.sun_disc;
  plan.settings.terms.ground = state_.ground;
  // The instant the sun shows; none once the sun was moved by hand.
  plan.dated_sun = date_follows_ ? dated_sun_ : std::nullopt;
  return plan;
}

// As `atmo render --backend gl` renders a frame (Sky::Screenshot: for hillaire and elek the frame
// pass without the disc, read back, the disc integrated over the pixels on the host; reference's
// estimate so far with its standard error), then the same writer.
void Viewer::Screenshot(const std::string& exr_path, const std::string& png_path) {
  if (sky_ == nullptr) throw Error("no sky shown yet: nothing to write");
  const auto start = std::chrono::steady_clock::now();
  cli::RenderPlan plan = CurrentPlan();
  Image standard_error;
  std::uint64_t samples_per_pixel = 0;
  Image image = sky_->Screenshot(plan.settings, &standard_error, &samples_per_pixel);
  drawn_generation_ = -1;  // the screenshot's frame (no disc) is in the frame textures now
  // The night sky, as `atmo render` adds it (reference's estimate has it: DrawsNight).
  UpdateNight();
  if (night_ != nullptr && night_->active() && !sky_->DrawsNight()) {
    AddNightSky(night_->Scaled(plan.model_parameters.solar_irradiance), plan.settings.camera, image);
    if (moon_) {
      // The moonlit sky, as `atmo render --backend gl` adds it: the frame for a sun in the
      // moon's direction without the disc, times the moon's irradiance, then the moon's disc.
      SetViewToMoon(*sky_);
      RenderSettings lit = plan.settings;
      lit.sun_elevation_deg = moon_place_.elevation_deg;
      lit.sun_azimuth_deg = moon_place_.azimuth_deg;
      lit.terms.sun_disc = false;
      const Image moonlit = sky_->Screenshot(lit, nullptr, nullptr);
      sky_->SetView(state_.altitude_m, state_.sun_elevation_deg, state_.sun_azimuth_deg, state_.ground, pass_timings_);
      if (plan.settings.terms.sun_disc) {
        AddMoonLight(*moon_, moonlit, *night_, plan.settings.camera, plan.model_parameters.solar_irradiance, image);
      } else {
        for (std::size_t i = 0; i < image.pixels.size(); ++i) {
          image.pixels[i] += moonlit.pixels[i] * static_cast<float>(moon_->relative_irradiance()[i % moonlit.channels]);
        }
      }
    }
  }
  // Reference's estimate has its own (smaller) size.
  plan.settings.camera.width = image.width;
  plan.settings.camera.height = image.height;
  const double render_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  cli::RenderCommand command = options_.render;
  // The PNG's exposure is the one on screen.
  command.exposure.reset();
  command.ev100.reset();
  command.auto_exposure = state_.auto_exposure;
  if (!state_.auto_exposure) command.ev100 = state_.ev100;
  // The --option flags of the shown model (none for a model other than --model's), with the
  // panel's hillaire options where they differ from them: what `atmo render --option ...` needs
  // to render this frame.
  cli::CommonOptions common = options_.common;
  common.model = shown_model_;
  if (shown_model_ != options_.common.model) common.options.clear();
  if (shown_model_ == "reference") common.backend = "cpu";  // the CPU's path tracer
  common.spectral = shown_spectral_ ? spectral_count_ : 0;
  if (shown_model_ == "hillaire") {
    const HillaireSettings flags = cli::GlHillaireSettings(common);
    const auto set_option = [&](const std::string& key, const std::string& value) {
      std::erase_if(common.options, [&](const std::string& o) { return o.rfind(key + "=", 0) == 0; });
      common.options.push_back(key + "=" + value);
    };
    if (settings_.sky_view_samples != flags.sky_view_samples) {
      set_option("sky_view_samples", std::to_string(settings_.sky_view_samples));
    }
    if (settings_.ray_march_samples != flags.ray_march_samples) {
      set_option("ray_march_samples", std::to_string(settings_.ray_march_samples));
    }
    if (settings_.multiple_scattering_directions != flags.multiple_scattering_directions) {
      set_option("multiple_scattering_directions", std::to_string(settings_.multiple_scattering_directions));
    }
    if (settings_.use_sky_view_lut != flags.use_sky_view_lut)
      set_option("sky_view", settings_.use_sky_view_lut ? "auto" : "off");
  }
  if (shown_model_ == "source4d") {
    // The panel's source4d options where they differ from the flags'.
    const ModelOptions flags = Source4dOptions(cli::GlSource4dSettings(common));
    for (const auto& [key, value] : Source4dOptions(shown_source4d_settings_)) {
      if (flags.at(key) == value) continue;
      std::erase_if(common.options, [&](const std::string& o) { return o.rfind(key + "=", 0) == 0; });
      common.options.push_back(key + "=" + value);
    }
  }
  command.width = image.width;
  command.height = image.height;
  cli::RenderOutputs outputs(common, command, plan, shown_model_);
  outputs.SetMetadata("atmo:writer", "atmo-viewer");
  if (shown_model_ == "source4d") {
    outputs.SetMetadata("atmo:source4dTables", shown_source4d_cpu_tables_ ? "cpu" : "gpu");
  }
  outputs.SetMetadata("atmo:viewerFrame", std::to_string(frame_));
  const bool monte_carlo = standard_error.width > 0;
  if (monte_carlo) {
    outputs.SetMetadata("atmo:standardErrorChannels", "stderr.NAME: the standard error of channel NAME (same unit), the EXR layer stderr");
    outputs.SetMetadata("atmo:samplesPerPixel", std::to_string(samples_per_pixel));
  }
  const std::vector<std::string> written =
      outputs.Write(exr_path, png_path, image, monte_carlo ? &standard_error : nullptr, render_ms);
  std::string files;
  for (const std::string& path : written) files += (files.empty() ? "" : ", ") + path;
  status_ = "wrote " + files;
  std::printf("atmo-viewer: frame %d: wrote %s (%dx%d %s)\n", frame_, files.c_str(), image.width, image.height,
              std::string(ToString(plan.settings.camera.kind)).c_str());
}

void Viewer::UpdateSky() {
  // A model chosen for a geometry it cannot show: simple needs the half-space of preset simple,
  // the others a planet (earth).
  if (state_.model != requested_model_ && !requested_model_.empty()) {
    const bool half_space = base_.geometry != Geometry::kSpherical;
    const char* preset = state_.model == "simple" && !half_space  ? "simple"
                         : state_.model != "simple" && half_space ? "earth"
                                                                  : nullptr;
    if (preset != nullptr) {
      LoadBase(Preset(preset));
      ResetAtmosphereKnobs(base_, state_);
      loaded_ = state_;
      const std::vector<std::string> presets = PresetNames();
      preset_index_ = static_cast<int>(std::find(presets.begin(), presets.end(), preset) - presets.begin());
    }
  }
  requested_model_ = state_.model;
  if (state_.spectral != base_spectral_) {
    // The RGB preset or its spectral form, the knobs kept: a knob at the loaded value of one form
    // is at the loaded value of the other.
    base_spectral_ = state_.spectral;
    base_ = base_spectral_ ? MakeSpectral(rgb_base_, spectral_count_) : rgb_base_;
    ViewState fresh = state_;
    ResetAtmosphereKnobs(base_, fresh);
    if (state_.mie_g == loaded_.mie_g) state_.mie_g = fresh.mie_g;
    if (state_.ground_albedo == loaded_.ground_albedo) state_.ground_albedo = fresh.ground_albedo;
    if (state_.ground_radius_m == loaded_.ground_radius_m) state_.ground_radius_m = fresh.ground_radius_m;
    loaded_ = fresh;
  }
  const bool wanted = sky_ == nullptr || !SameKnobs(state_, shown_knobs_) || !(base_ == current_base_) ||
                      settings_changed_ || state_.model != shown_model_;
  if (!wanted) {
    pending_.reset();  // a change undone before its sky was complete
    if (options_.recompute_every_frame) {
      sky_->Recompute(pass_timings_);
      view_dirty_ = true;
    }
    return;
  }
  try {
    // All or nothing: the new sky replaces the shown one only once all of its tables are built.
    AtmosphereParameters next = ApplyAtmosphereKnobs(base_, loaded_, state_);
    if (pending_ == nullptr || state_.model != pending_model_ || !(next == pending_parameters_) ||
        settings_generation_ != pending_settings_generation_) {
      pending_.reset();
      pending_ = MakeSky(state_.model, next);
      pending_model_ = state_.model;
      pending_parameters_ = next;
      pending_settings_generation_ = settings_generation_;
    }
    if (!pending_->Build(options_.build_budget_ms, pass_timings_)) return;  // shown in a later frame
    sky_ = std::move(pending_);
    ++sky_generation_;
    shown_model_ = pending_model_;
    current_ = std::move(next);
    current_base_ = base_;
    current_rgb_base_ = rgb_base_;
    shown_spectral_ = base_spectral_;
    current_loaded_ = loaded_;
    current_preset_index_ = preset_index_;
    shown_settings_ = settings_;
    shown_source4d_settings_ = source4d_settings_;
    shown_source4d_cpu_tables_ = source4d_cpu_tables_;
    settings_changed_ = false;
    shown_knobs_ = state_;
    UpdateDisplayWeights();
    view_dirty_ = true;
    metered_ = false;
  } catch (const Error& error) {
    pending_.reset();
    if (sky_ == nullptr) throw;  // the first sky: nothing to go back to
    // A knob out of bounds, a preset or config the model refuses: back to what is shown.
    status_ = error.what();
    base_ = current_base_;
    rgb_base_ = current_rgb_base_;
    base_spectral_ = shown_spectral_;
    state_.spectral = shown_spectral_;
    loaded_ = current_loaded_;
    preset_index_ = current_preset_index_;
    settings_ = shown_settings_;
    source4d_settings_ = shown_source4d_settings_;
    source4d_cpu_tables_ = shown_source4d_cpu_tables_;
    settings_changed_ = false;
    state_.model = shown_model_;
    requested_model_ = shown_model_;
    CopyKnobs(shown_knobs_, state_);
  }
}

void Viewer::UpdateCompareSky() {
  if (compare_model_.empty() || sky_ == nullptr) {
    compare_sky_.reset();
    compare_pending_.reset();
    return;
  }
  if (compare_sky_ != nullptr && compare_shown_model_ == compare_model_ && compare_parameters_ == current_) {
    compare_pending_.reset();
    return;
  }
  try {
    if (compare_pending_ == nullptr || compare_pending_model_ != compare_model_ ||
        !(compare_pending_parameters_ == current_)) {
      compare_pending_.reset();
      compare_pending_ = MakeSky(compare_model_, current_);
      compare_pending_model_ = compare_model_;
      compare_pending_parameters_ = current_;
    }
    if (!compare_pending_->Build(options_.build_budget_ms, pass_timings_)) return;
    compare_sky_ = std::move(compare_pending_);
    compare_shown_model_ = compare_pending_model_;
    compare_parameters_ = compare_pending_parameters_;
    compare_view_dirty_ = true;
  } catch (const Error& error) {
    // A model that cannot show this atmosphere (simple against a planet): compare mode off.
    status_ = std::string("compare: ") + error.what();
    compare_pending_.reset();
    compare_sky_.reset();
    compare_model_.clear();
  }
}

// The scale of the difference view (log-symmetric, ticks at +-1 %, 10 %, 100 %) or of the
// luminance false colour (log10 cd/m^2, a tick per decade), below the panel.
void Viewer::DrawColourBar(int mode, bool false_colour) {
  const ImGuiIO& io = ImGui::GetIO();
  ImGui::SetNextWindowPos(ImVec2(10.0f, io.DisplaySize.y - 90.0f), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(420.0f, 80.0f), ImGuiCond_FirstUseEver);
  ImGui::Begin(mode == 2 ? "(B - A) / A" : "luminance, log10 cd/m^2");
  ImDrawList* draw = ImGui::GetWindowDrawList();
  const ImVec2 origin = ImGui::GetCursorScreenPos();
  const float width = std::max(ImGui::GetContentRegionAvail().x, 50.0f);
  const float height = 18.0f;
  constexpr int kSteps = 128;
  for (int i = 0; i < kSteps; ++i) {
    const float u = (i + 0.5f) / kSteps;
    const ImU32 c = mode == 2 ? DivergingColour(2.0f * u - 1.0f) : SequentialColour(u);
    draw->AddRectFilled(ImVec2(origin.x + width * i / kSteps, origin.y),
                        ImVec2(origin.x + width * (i + 1) / kSteps, origin.y + height), c);
  }
  const auto tick = [&](float u, const char* label) {
    const float x = origin.x + width * u;
    draw->AddLine(ImVec2(x, origin.y + height), ImVec2(x, origin.y + height + 4.0f), IM_COL32(255, 255, 255, 255));
    const float text = ImGui::CalcTextSize(label).x;
    draw->AddText(ImVec2(std::clamp(x - text / 2.0f, origin.x, origin.x + width - text), origin.y + height + 5.0f),
                  IM_COL32(255, 255, 255, 255), label);
  };
  if (mode == 2) {
    // t = sign(d) (log10 |d| + 3) / 3 at u = (t + 1) / 2.
    const char* labels[7] = {"-100%", "-10%", "-1%", "0", "+1%", "+10%", "+100%"};
    for (int k = 0; k < 7; ++k) tick(k / 6.0f, labels[k]);
  } else if (false_colour) {
    for (int decade = static_cast<int>(kLogLuminanceRange[0]); decade <= static_cast<int>(kLogLuminanceRange[1]);
         ++decade) {
      const std::string label = std::to_string(decade);
      tick((decade - kLogLuminanceRange[0]) / (kLogLuminanceRange[1] - kLogLuminanceRange[0]), label.c_str());
    }
  }
  ImGui::Dummy(ImVec2(width, height + 22.0f));
  ImGui::End();
}

void Viewer::FollowDate() {
  if (!date_follows_) return;
  const double julian_day = plan_.dated_sun->julian_day_utc + state_.date_hours / 24.0;
  if (dated_sun_ && dated_sun_->julian_day_utc == julian_day) return;
  dated_sun_ = cli::SunAt(options_.render.sun, julian_day);
  state_.sun_elevation_deg = dated_sun_->position.elevation_deg;
  state_.sun_azimuth_deg = dated_sun_->position.azimuth_deg;
}

// The sun below the horizon (above it the night sky is less than 1e-6 of the sky's light: at sun
// 0 degrees the clear sky is some 10^3 cd/m^2, the moonless night sky 2e-4), a sky that does not
// draw the night itself (reference does: GiveNight), a planet's atmosphere.
bool Viewer::NightShown() const { return sky_ != nullptr && NightOnGpu(*sky_); }

bool Viewer::NightOnGpu(const Sky& sky) const {
  return night_ != nullptr && night_->active() && !sky.DrawsNight() && state_.sun_elevation_deg < 0.0;
}

// As `atmo render --model reference` passes them to the model: the night sky and the moon at any
// sun elevation (its glow's scattered light is traced only with the sun below the horizon).
void Viewer::GiveNight(Sky& sky) const {
  if (!sky.DrawsNight()) return;
  const bool active = night_ != nullptr && night_->active();
  sky.SetNight(active ? night_ : nullptr, active ? moon_ : nullptr);
}

void Viewer::UpdateNight() {
  if (sky_ == nullptr) return;
  const std::optional<cli::SunAtInstant> dated = date_follows_ ? dated_sun_ : std::nullopt;
  const std::vector<double> key = {static_cast<double>(sky_generation_), state_.altitude_m, state_.sun_elevation_deg,
                                   state_.sun_azimuth_deg, dated ? dated->julian_day_utc : -1.0};
  if (key == night_key_) return;
  night_key_ = key;
  night_.reset();
  if (current_.geometry != Geometry::kSpherical) {
    night_gl_->Set(NightSky::Folded());
    moon_.reset();
    return;
  }
  const glm::dvec3 sun = SunDirection(state_.sun_elevation_deg, state_.sun_azimuth_deg);
  const cli::SunOptions& place = options_.render.sun;
  const cli::SunOptions& place_sun = place;
  const glm::dvec3 pole = dated ? EclipticPoleDirection(dated->julian_day_utc, *place.latitude_deg, *place.longitude_deg)
                                : glm::dvec3(0.0);
  night_ = std::make_shared<NightSky>(current_, std::max(state_.altitude_m, 0.0), sun, pole);
  moon_.reset();
  moon_disc_key_.clear();
  if (const std::optional<MoonPosition> place =
          cli::ResolveMoon(options_.render.moon, place_sun, state_.sun_azimuth_deg,
                           dated ? std::optional<double>(dated->julian_day_utc) : std::nullopt)) {
    moon_place_ = *place;
    moon_ = std::make_shared<const Moon>(SunDirection(place->elevation_deg, place->azimuth_deg),
                                         place->phase_angle_deg, place->distance_km, current_.wavelengths_nm, sun);
  }
  const CelestialFrame frame = dated ? CelestialFrame::FromDate(dated->julian_day_utc, *place.latitude_deg,
                                                                *place.longitude_deg)
                                     : CelestialFrame::FromSun(sun);
  if (stars_ != nullptr) {
    night_->SetStars(*stars_, frame);
  } else {
    night_->SetFrame(frame);
  }
  night_gl_->Set(night_->Scaled(CurrentPlan().model_parameters.solar_irradiance));
}

void Viewer::SetViewToMoon(Sky& sky) {
  sky.SetView(state_.altitude_m, moon_place_.elevation_deg, moon_place_.azimuth_deg, state_.ground, pass_timings_);
}

void Viewer::RenderMoonlit(Sky& sky, const Camera& camera, const RadianceTerms& terms,
                           std::vector<gl::GpuTexture>& moon_frames) {
  SetViewToMoon(sky);
  RadianceTerms moon_terms = terms;
  moon_terms.sun_disc = false;
  sky.RenderFrame(camera, moon_terms, pass_timings_);
  moon_frames.resize(sky.batch_count());
  for (std::size_t b = 0; b < sky.batch_count(); ++b) {
    const gl::GpuTexture& frame = sky.frame_texture(b);
    const shared::ivec2 size = frame.size2();
    if (moon_frames[b].empty() || moon_frames[b].size2().x != size.x || moon_frames[b].size2().y != size.y) {
      moon_frames[b] = gl::GpuTexture::Make2D(size);
    }
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
    glCopyImageSubData(frame.id(), GL_TEXTURE_2D, 0, 0, 0, 0, moon_frames[b].id(), GL_TEXTURE_2D, 0, 0, 0, 0, size.x,
                       size.y, 1);
  }
  sky.SetView(state_.altitude_m, state_.sun_elevation_deg, state_.sun_azimuth_deg, state_.ground, pass_timings_);
}

void Viewer::AddMoon(const Sky& sky, const Camera& camera, const std::vector<gl::GpuTexture>& moon_frames) {
  const std::vector<double>& solar = CurrentPlan().model_parameters.solar_irradiance;
  const glm::dvec3& d = moon_->direction();
  const std::vector<double> key = {static_cast<double>(camera.kind), static_cast<double>(camera.width),
                                   static_cast<double>(camera.height), camera.fov_deg, camera.yaw_deg, camera.pitch_deg,
                                   d.x, d.y, d.z, moon_->phase_angle_deg(), static_cast<double>(sky_generation_)};
  if (key != moon_disc_key_) {
    // The disc over the whole frame on the host, then only the patch that holds it.
    moon_disc_key_ = key;
    Image full(camera.width, camera.height, static_cast<int>(solar.size()));
    AddMoonDiscLight(*moon_, *night_, camera, solar, full);
    int x0 = camera.width, y0 = camera.height, x1 = -1, y1 = -1;
    const std::size_t n = solar.size();
    for (int y = 0; y < camera.height; ++y) {
      for (int x = 0; x < camera.width; ++x) {
        const float* p = &full.pixels[(static_cast<std::size_t>(y) * camera.width + x) * n];
        if (std::any_of(p, p + n, [](float v) { return v != 0.0f; })) {
          x0 = std::min(x0, x);
          y0 = std::min(y0, y);
          x1 = std::max(x1, x);
          y1 = std::max(y1, y);
        }
      }
    }
    moon_disc_ = x1 < 0 ? Image() : Image(x1 - x0 + 1, y1 - y0 + 1, static_cast<int>(n));
    moon_disc_origin_ = {std::max(x0, 0), std::max(y0, 0)};
    for (int y = 0; y < moon_disc_.height; ++y) {
      for (int x = 0; x < moon_disc_.width; ++x) {
        for (std::size_t c = 0; c < n; ++c) {
          moon_disc_.pixels[(static_cast<std::size_t>(y) * moon_disc_.width + x) * n + c] =
              full.pixels[(static_cast<std::size_t>(y0 + y) * camera.width + x0 + x) * n + c];
        }
      }
    }
  }
  std::vector<const gl::GpuTexture*> frames, moonlit;
  std::vector<shared::vec3> scale;
  for (std::size_t b = 0; b < sky.batch_count(); ++b) {
    frames.push_back(&sky.frame_texture(b));
    moonlit.push_back(&moon_frames.at(b));
    scale.push_back(BatchValues(moon_->relative_irradiance(), b));
  }
  night_gl_->AddMoon(frames, moonlit, scale, moon_disc_, moon_disc_origin_, pass_timings_);
}

void Viewer::AddNight(const Sky& sky, const Camera& camera) {
  if (sky.batch_count() > night_gl_->batch_count()) return;  // a compared sky of other channels
  std::vector<const gl::GpuTexture*> frames;
  for (std::size_t b = 0; b < sky.batch_count(); ++b) frames.push_back(&sky.frame_texture(b));
  night_gl_->Add(ToSharedCamera(camera), frames, pass_timings_);
}

void Viewer::HandleInput(double dt_s) {
  GLFWwindow* window = static_cast<GLFWwindow*>(context_->window());
  if (window == nullptr) return;  // --offscreen: no input
  const ImGuiIO& io = ImGui::GetIO();
  double x = 0.0;
  double y = 0.0;
  glfwGetCursorPos(window, &x, &y);
  const bool free_mouse = !io.WantCaptureMouse;
  const bool left = glfwGetMouseButton(window, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS;
  const bool right = glfwGetMouseButton(window, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS;
  const bool shift =
      glfwGetKey(window, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS || glfwGetKey(window, GLFW_KEY_RIGHT_SHIFT) == GLFW_PRESS;
  // Right button (or shift + left): the sun goes where the mouse points on the sky.
  const bool sun_button = right || (left && shift);
  if (sun_button && (dragging_sun_ || free_mouse)) {
    dragging_sun_ = true;
    int width = 0;
    int height = 0;
    glfwGetFramebufferSize(window, &width, &height);
    if (PutSunAtPixel(state_, width, height, x, y)) date_follows_ = false;
  } else {
    dragging_sun_ = false;
  }
  // Left button on the split line (compare split): the line follows the mouse.
  int window_width = 1;
  int window_height = 1;
  glfwGetWindowSize(window, &window_width, &window_height);
  const bool split_shown = compare_sky_ != nullptr && compare_view_ == 1;
  if (left && !shift && split_shown &&
      (dragging_split_ || (free_mouse && !dragging_view_ && std::abs(x - split_ * window_width) <= 6.0))) {
    dragging_split_ = true;
    split_ = std::clamp(x / std::max(window_width, 1), 0.0, 1.0);
  } else {
    dragging_split_ = false;
  }
  // Left button: look around (the sky follows the mouse).
  if (left && !shift && !dragging_split_ && (dragging_view_ || free_mouse)) {
    if (dragging_view_) {
      int width = 1;
      int height = 1;
      glfwGetWindowSize(window, &width, &height);
      const double degrees_per_pixel =
          state_.camera == CameraKind::kPerspective ? state_.fov_deg / std::max(width, 1) : 360.0 / std::max(width, 1);
      state_.yaw_deg = std::fmod(state_.yaw_deg - (x - last_x_) * degrees_per_pixel + 720.0, 360.0);
      state_.pitch_deg = std::clamp(state_.pitch_deg + (y - last_y_) * degrees_per_pixel, -90.0, 90.0);
    }
    dragging_view_ = true;
  } else {
    dragging_view_ = false;
  }
  last_x_ = x;
  last_y_ = y;
  // Altitude: the wheel, Page Up / Page Down or Q / E (held: continuous, a factor e per second).
  if (free_mouse && io.MouseWheel != 0.0f) state_.altitude_m = StepAltitude(state_.altitude_m, 0.25 * io.MouseWheel);
  if (!io.WantCaptureKeyboard) {
    const auto held = [&](int key) { return glfwGetKey(window, key) == GLFW_PRESS; };
    if (held(GLFW_KEY_PAGE_UP) || held(GLFW_KEY_E)) state_.altitude_m = StepAltitude(state_.altitude_m, 1.5 * dt_s);
    if (held(GLFW_KEY_PAGE_DOWN) || held(GLFW_KEY_Q)) state_.altitude_m = StepAltitude(state_.altitude_m, -1.5 * dt_s);
    const double turn = 60.0 * dt_s;  // degrees per second
    if (held(GLFW_KEY_LEFT) || held(GLFW_KEY_A)) state_.yaw_deg = std::fmod(state_.yaw_deg - turn + 360.0, 360.0);
    if (held(GLFW_KEY_RIGHT) || held(GLFW_KEY_D)) state_.yaw_deg = std::fmod(state_.yaw_deg + turn, 360.0);
    if (held(GLFW_KEY_UP) || held(GLFW_KEY_W)) state_.pitch_deg = std::min(90.0, state_.pitch_deg + turn);
    if (held(GLFW_KEY_DOWN) || held(GLFW_KEY_S)) state_.pitch_deg = std::max(-90.0, state_.pitch_deg - turn);
    if (held(GLFW_KEY_ESCAPE)) glfwSetWindowShouldClose(window, GLFW_TRUE);
  }
}

void Viewer::DrawPanels() {
  // The panel scales with the window: at most 26 % of its width (between 220 and 340 px) and 60 %
  // of its height (it scrolls beyond), and it starts collapsed to its title bar in a window under
  // 900 px wide (a 720 x 720 fisheye), where it would hide the sky. Click the title to open it.
  const ImVec2 display = ImGui::GetIO().DisplaySize;
  const float width = std::clamp(0.26f * display.x, 220.0f, 340.0f);
  ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(width, 0.6f * display.y), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSizeConstraints(ImVec2(200.0f, 60.0f),
                                      ImVec2(std::max(220.0f, 0.4f * display.x), std::max(60.0f, 0.9f * display.y)));
  ImGui::SetNextWindowCollapsed(display.x < 900.0f, ImGuiCond_FirstUseEver);
  ImGui::Begin("atmo-viewer");
  ImGui::Text("%.2f ms/frame (%.1f fps), %s", frame_ms_, frame_ms_ > 0.0 ? 1000.0 / frame_ms_ : 0.0,
              context_->renderer().c_str());
  {
    // The model: a new one is built while the last one stays on screen (elek: a progress bar).
    const std::vector<std::string>& models = ViewerModelNames();
    int index = static_cast<int>(std::find(models.begin(), models.end(), state_.model) - models.begin());
    if (ImGui::Combo("model", &index, "hillaire\0elek\0simple\0reference\0source4d\0")) state_.model = models[index];
    if (pending_ != nullptr) {
      const std::string label = "building " + pending_model_;
      ImGui::ProgressBar(static_cast<float>(pending_->progress()), ImVec2(-1.0f, 0.0f), label.c_str());
    }
    if (sky_ != nullptr && !sky_->Status().empty()) ImGui::TextWrapped("%s", sky_->Status().c_str());
  }
  if (ImGui::CollapsingHeader("GPU passes (ms)")) {
    for (const PassTiming& pass : shown_timings_.entries()) {
      ImGui::Text("%-26s %8.2f", pass.name.c_str(), pass.last_ms);
    }
  }
  if (ImGui::CollapsingHeader("Camera and sun", ImGuiTreeNodeFlags_DefaultOpen)) {
    int kind = static_cast<int>(state_.camera);
    ImGui::Combo("camera", &kind, "perspective\0fisheye\0equirect\0");
    state_.camera = static_cast<CameraKind>(kind);
    float v = static_cast<float>(state_.altitude_m);
    if (ImGui::SliderFloat("altitude m", &v, 0.0f, kMaxSliderAltitude_m, "%.0f", ImGuiSliderFlags_Logarithmic)) {
      state_.altitude_m = v;
    }
    v = static_cast<float>(state_.yaw_deg);
    if (ImGui::SliderFloat("yaw", &v, 0.0f, 360.0f, "%.1f")) state_.yaw_deg = v;
    // Pitch and field of view are the perspective camera's (the CLI says so for --pitch, --fov).
    if (state_.camera == CameraKind::kPerspective) {
      v = static_cast<float>(state_.pitch_deg);
      if (ImGui::SliderFloat("pitch", &v, -90.0f, 90.0f, "%.1f")) state_.pitch_deg = v;
      v = static_cast<float>(state_.fov_deg);
      if (ImGui::SliderFloat("fov", &v, 5.0f, 170.0f, "%.1f")) state_.fov_deg = v;
    }
    v = static_cast<float>(state_.sun_elevation_deg);
    if (ImGui::SliderFloat("sun elevation", &v, -90.0f, 90.0f, "%.2f")) {
      state_.sun_elevation_deg = v;
      date_follows_ = false;
    }
    v = static_cast<float>(state_.sun_azimuth_deg);
    if (ImGui::SliderFloat("sun azimuth", &v, 0.0f, 360.0f, "%.1f")) {
      state_.sun_azimuth_deg = v;
      date_follows_ = false;
    }
    if (plan_.dated_sun) {
      // --date, --latitude, --longitude: the sun of that place at the date plus an offset.
      ImGui::Checkbox("sun follows the date", &date_follows_);
      v = static_cast<float>(state_.date_hours);
      if (ImGui::SliderFloat("hours after --date", &v, -24.0f, 24.0f, "%.2f")) {
        state_.date_hours = v;
        date_follows_ = true;
      }
      if (ImGui::Button(playing_ ? "pause" : "play")) {
        playing_ = !playing_;
        if (playing_) date_follows_ = true;
      }
      ImGui::SameLine();
      float speed = static_cast<float>(play_speed_);
      if (ImGui::SliderFloat("hours/s", &speed, 0.01f, 10.0f, "%.2f", ImGuiSliderFlags_Logarithmic))
        play_speed_ = speed;
      if (date_follows_ && dated_sun_) ImGui::Text("%s", dated_sun_->date_utc.c_str());
    }
    ImGui::Checkbox("sun disc", &state_.sun_disc);
    ImGui::SameLine();
    ImGui::Checkbox("lit ground", &state_.ground);
  }
  if (ImGui::CollapsingHeader("Atmosphere", ImGuiTreeNodeFlags_DefaultOpen)) {
    const std::vector<std::string> presets = PresetNames();
    const char* shown = preset_index_ >= 0 ? presets[preset_index_].c_str() : "(config)";
    if (ImGui::BeginCombo("preset", shown)) {
      for (std::size_t i = 0; i < presets.size(); ++i) {
        if (ImGui::Selectable(presets[i].c_str(), static_cast<int>(i) == preset_index_)) {
          // Made in the next frame; a preset hillaire refuses (simple's half-space) is reported there.
          preset_index_ = static_cast<int>(i);
          LoadBase(Preset(presets[i]));
          ResetAtmosphereKnobs(base_, state_);
          loaded_ = state_;
        }
      }
      ImGui::EndCombo();
    }
    const auto slider = [](const char* label, double& value, float min, float max, bool logarithmic) {
      float f = static_cast<float>(value);
      if (ImGui::SliderFloat(label, &f, min, max, "%.3f", logarithmic ? ImGuiSliderFlags_Logarithmic : 0)) value = f;
    };
    slider("Rayleigh density", state_.rayleigh_density, 0.0f, 10.0f, true);
    slider("Mie density", state_.mie_density, 0.0f, 50.0f, true);
    slider("ozone density", state_.ozone_density, 0.0f, 10.0f, true);
    slider("Mie g", state_.mie_g, -0.99f, 0.99f, false);
    slider("ground albedo", state_.ground_albedo, 0.0f, 1.0f, false);
    float radius_km = static_cast<float>(state_.ground_radius_m / 1000.0);
    if (ImGui::SliderFloat("planet radius km", &radius_km, 100.0f, 100000.0f, "%.0f", ImGuiSliderFlags_Logarithmic)) {
      state_.ground_radius_m = 1000.0 * radius_km;
    }
    const std::string spectral_label = "spectral (" + std::to_string(spectral_count_) + " wavelengths)";
    ImGui::Checkbox(spectral_label.c_str(), &state_.spectral);
    if (ImGui::Button("reset atmosphere")) {
      ResetAtmosphereKnobs(base_, state_);
    }
  }
  if (state_.model == "hillaire" && ImGui::CollapsingHeader("hillaire options")) {
    HillaireSettings s = settings_;
    ImGui::SliderInt("sky_view_samples", &s.sky_view_samples, 1, 128);
    ImGui::SliderInt("ray_march_samples", &s.ray_march_samples, 1, 256);
    ImGui::SliderInt("multiple_scattering_directions", &s.multiple_scattering_directions, 1, 256);
    ImGui::Checkbox("sky_view table", &s.use_sky_view_lut);
    if (s.sky_view_samples != settings_.sky_view_samples || s.ray_march_samples != settings_.ray_march_samples ||
        s.multiple_scattering_directions != settings_.multiple_scattering_directions ||
        s.use_sky_view_lut != settings_.use_sky_view_lut) {
      settings_ = s;
      settings_changed_ = true;  // every table again, with the new settings
      ++settings_generation_;
    }
  }
  if (state_.model == "source4d" && ImGui::CollapsingHeader("source4d options")) {
    // Applied on Enter (a typed value) or a +/- click; every table again, the last sky shown
    // until they are built. Values the model refuses are shown as the error and not applied.
    const cpu::Source4dSettings& t = source4d_settings_.tables;
    int table[4] = {t.r_size, t.mu_size, t.mu_s_size, t.phi_size};
    int gather[2] = {t.gather_zeniths, t.gather_azimuths};
    int gather_samples = t.gather_samples;
    int orders = t.orders;
    bool tail = t.tail;
    int samples = source4d_settings_.samples;
    constexpr ImGuiInputTextFlags kEnter = ImGuiInputTextFlags_EnterReturnsTrue;
    bool changed = ImGui::InputInt4("table r mu mu_s phi", table, kEnter);
    changed |= ImGui::InputInt2("gather zeniths azimuths", gather, kEnter);
    changed |= ImGui::InputInt("gather_samples", &gather_samples, 1, 8, kEnter);
    changed |= ImGui::InputInt("orders", &orders, 1, 1, kEnter);
    changed |= ImGui::Checkbox("tail", &tail);
    changed |= ImGui::InputInt("samples (per pixel)", &samples, 1, 8, kEnter);
    if (changed) {
      ModelOptions options = Source4dOptions(source4d_settings_);
      options["table"] = cli::Format("%dx%dx%dx%d", table[0], table[1], table[2], table[3]);
      options["gather"] = cli::Format("%dx%d", gather[0], gather[1]);
      options["gather_samples"] = std::to_string(gather_samples);
      options["orders"] = std::to_string(orders);
      options["tail"] = tail ? "on" : "off";
      options["samples"] = std::to_string(samples);
      try {
        const Source4dModelSettings next = Source4dModelSettings::FromOptions(options);
        if (Source4dOptions(next) != Source4dOptions(source4d_settings_)) {
          source4d_settings_ = next;
          settings_changed_ = true;
          ++settings_generation_;
        }
      } catch (const Error& error) {
        status_ = error.what();
      }
    }
    // Where the tables are built (--source4d-tables): a change builds them again there.
    int where = source4d_cpu_tables_ ? 1 : 0;
    if (ImGui::Combo("tables on", &where, "gpu (GL passes)\0cpu (worker thread)\0") &&
        (where == 1) != source4d_cpu_tables_) {
      source4d_cpu_tables_ = where == 1;
      settings_changed_ = true;
      ++settings_generation_;
    }
    if (pending_ != nullptr && pending_model_ == "source4d") {
      ImGui::Text("building the tables: %.0f %%", 100.0 * pending_->progress());
      const std::string line = pending_->BuildStatus();
      if (!line.empty()) ImGui::TextWrapped("%s", line.c_str());
    }
  }
  if (ImGui::CollapsingHeader("Display", ImGuiTreeNodeFlags_DefaultOpen)) {
    ImGui::Checkbox("auto-exposure", &state_.auto_exposure);
    float ev = static_cast<float>(state_.auto_exposure ? metered_ev100_ : state_.ev100);
    if (ImGui::SliderFloat("EV100", &ev, -10.0f, 20.0f, "%.2f")) {
      state_.ev100 = ev;
      state_.auto_exposure = false;
    }
    int op = static_cast<int>(mapping_.op);
    ImGui::Combo("tone mapping", &op, "exp\0aces\0none\0agx\0");
    mapping_.op = static_cast<ToneMapper>(op);
    ImGui::Checkbox("per channel", &mapping_.per_channel);
  }
  if (ImGui::CollapsingHeader("Compare", ImGuiTreeNodeFlags_DefaultOpen)) {
    // Model B beside or against the shown model A, on the same atmosphere and view.
    const char* names[] = {"none", "hillaire", "elek", "simple", "reference", "source4d"};
    int index = 0;
    for (int i = 1; i < 6; ++i) {
      if (compare_model_ == names[i]) index = i;
    }
    if (ImGui::Combo("compare with", &index, names, 6)) compare_model_ = index == 0 ? "" : names[index];
    ImGui::RadioButton("split", &compare_view_, 1);
    ImGui::SameLine();
    ImGui::RadioButton("difference (B - A) / A", &compare_view_, 2);
    float split = static_cast<float>(split_);
    if (ImGui::SliderFloat("split", &split, 0.0f, 1.0f, "%.3f")) split_ = split;
    ImGui::Checkbox("false colour: luminance", &false_colour_);
    if (compare_pending_ != nullptr) {
      const std::string label = "building " + compare_pending_model_;
      ImGui::ProgressBar(static_cast<float>(compare_pending_->progress()), ImVec2(-1.0f, 0.0f), label.c_str());
    }
    if (compare_sky_ != nullptr && !compare_sky_->Status().empty()) {
      ImGui::TextWrapped("B: %s", compare_sky_->Status().c_str());
    }
  }
  if (ImGui::CollapsingHeader("Files", ImGuiTreeNodeFlags_DefaultOpen)) {
    ImGui::InputText("config", config_path_, sizeof config_path_);
    if (ImGui::Button("save config")) {
      try {
        WriteConfig(config_path_, current_);
        status_ = std::string("wrote ") + config_path_;
      } catch (const Error& error) {
        status_ = error.what();
      }
    }
    ImGui::SameLine();
    if (ImGui::Button("load config")) {
      try {
        LoadBase(LoadParametersFile(config_path_));
        preset_index_ = -1;
        ResetAtmosphereKnobs(base_, state_);
        loaded_ = state_;
        status_ = std::string("loaded ") + config_path_;
      } catch (const Error& error) {
        status_ = error.what();
      }
    }
    ImGui::InputText("screenshot", screenshot_name_, sizeof screenshot_name_);
    if (ImGui::Button("screenshot EXR + PNG")) {
      try {
        Screenshot(std::string(screenshot_name_) + ".exr", std::string(screenshot_name_) + ".png");
      } catch (const Error& error) {
        status_ = error.what();
      }
    }
  }
  if (!status_.empty()) ImGui::TextWrapped("%s", status_.c_str());
  ImGui::End();
}

void Viewer::ReadTimings(bool wait) {
  // The last timed frame's GPU times (kTimedEvery frames ago: ready unless the GPU is that far
  // behind, when they are waited for).
  if (!timings_.Collect(wait)) timings_.Collect(true);
  if (timings_frame_ >= 0) {
    shown_timings_ = timings_;
    if (timings_frame_ > 0) {
      for (const PassTiming& pass : timings_.entries()) run_timings_.Add(pass.name, pass.last_ms);
    }
  }
  timings_.Clear();
  timings_frame_ = -1;
}

int Viewer::Run() {
  GLFWwindow* window = static_cast<GLFWwindow*>(context_->window());
  double frame_ms_sum = 0.0;
  int timed_frames = 0;
  auto last = std::chrono::steady_clock::now();
  const int frames = options_.frames;
  const std::string final_exr = options_.render.exr_path;
  const std::string final_png = options_.render.png_path;
  // With --frames N the run ends at frame N - 1, or later when the shown sky is not final yet
  // (elek's tables still building, reference short of --spp).
  for (frame_ = 0;; ++frame_) {
    if (window != nullptr && glfwWindowShouldClose(window)) break;
    // While a thread builds the next sky and nothing on screen changes, the loop waits for input
    // (up to 0.1 s) instead of drawing the same window again at once: on a software GL a window of
    // 1280x720 costs ~50 ms of both cores (display, panels, swap), which the build needs more.
    constexpr double kBuildWaitS = 0.1;
    if (window == nullptr) {
      if (waiting_for_build_) std::this_thread::sleep_for(std::chrono::duration<double>(kBuildWaitS));
    } else if (waiting_for_build_) {
      glfwWaitEventsTimeout(kBuildWaitS);
    } else {
      glfwPollEvents();
    }
    waiting_for_build_ = false;
    const auto now = std::chrono::steady_clock::now();
    const double dt_s = std::chrono::duration<double>(now - last).count();
    last = now;
    const std::vector<std::string> shots = ApplyScript(script_, frame_, state_);

    ImGui_ImplOpenGL3_NewFrame();
    if (window != nullptr) {
      ImGui_ImplGlfw_NewFrame();
    } else {
      ImGuiIO& io = ImGui::GetIO();
      io.DisplaySize = ImVec2(static_cast<float>(offscreen_->width()), static_cast<float>(offscreen_->height()));
      io.DeltaTime = dt_s > 0.0 ? static_cast<float>(dt_s) : 1.0f / 60.0f;
    }
    ImGui::NewFrame();
    HandleInput(dt_s);
    if (!options_.no_panels) {
      DrawPanels();
      const int mode = compare_sky_ != nullptr ? compare_view_ : 0;
      if (mode == 2 || false_colour_) DrawColourBar(mode, false_colour_);
    }
    ImGui::Render();
    if (playing_ && date_follows_) state_.date_hours += play_speed_ * dt_s;
    FollowDate();

    // The passes are timed every kTimedEvery-th frame (a timer waits for the GPU: glFinish on
    // llvmpipe); the panel shows the last timed frame's.
    const bool timed = frame_ % kTimedEvery == 1 % kTimedEvery;
    pass_timings_ = timed ? &timings_ : nullptr;
    if (timed) ReadTimings(/*wait=*/false);
    UpdateSky();
    UpdateCompareSky();
    const bool view_changed = view_dirty_ || state_.altitude_m != built_.altitude_m ||
                              state_.sun_elevation_deg != built_.sun_elevation_deg ||
                              state_.sun_azimuth_deg != built_.sun_azimuth_deg || state_.ground != built_.ground;
    if (sky_ != nullptr && view_changed) {
      try {
        sky_->SetView(state_.altitude_m, state_.sun_elevation_deg, state_.sun_azimuth_deg, state_.ground,
                      pass_timings_);
      } catch (const Error& error) {
        // An altitude the model refuses (below elek's ground): back to the last one.
        status_ = error.what();
        state_.altitude_m = built_.altitude_m;
        sky_->SetView(state_.altitude_m, state_.sun_elevation_deg, state_.sun_azimuth_deg, state_.ground,
                      pass_timings_);
      }
      view_dirty_ = false;
    }
    if (compare_sky_ != nullptr && (view_changed || compare_view_dirty_)) {
      try {
        compare_sky_->SetView(state_.altitude_m, state_.sun_elevation_deg, state_.sun_azimuth_deg, state_.ground,
                              pass_timings_);
      } catch (const Error& error) {
        status_ = std::string("compare: ") + error.what();
        compare_sky_.reset();
        compare_model_.clear();
      }
      compare_view_dirty_ = false;
    }
    const bool last_frame = frames > 0 && frame_ >= frames - 1 && Settled();
    built_ = state_;
    int width = 0;
    int height = 0;
    if (window != nullptr) {
      glfwGetFramebufferSize(window, &width, &height);
    } else {
      width = offscreen_->width();
      height = offscreen_->height();
    }
    // A screenshot asked for before any sky can be written (elek's first tables, reference's
    // first pass) waits for the first frame that has one.
    waiting_shots_.insert(waiting_shots_.end(), shots.begin(), shots.end());
    const bool can_write = sky_ != nullptr && sky_->HasFrame();
    const std::vector<std::string> ready = can_write ? std::move(waiting_shots_) : std::vector<std::string>{};
    if (can_write) waiting_shots_.clear();
    for (const std::string& path : ready) {
      const std::string lower = path.size() >= 4 ? path.substr(path.size() - 4) : path;
      if (lower == ".exr")
        Screenshot(path, "");
      else if (lower == ".png")
        Screenshot("", path);
      else
        throw Error("script screenshot '" + path + "' must end in .exr or .png");
    }
    if (last_frame && (!final_exr.empty() || !final_png.empty())) {
      Screenshot(final_exr, final_png);
    }
    if (sky_ == nullptr) {
      // Nothing built yet (elek's first tables): a black window under the panels.
      glViewport(0, 0, width, height);
      glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
      glClear(GL_COLOR_BUFFER_BIT);
      ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    } else if (width > 0 && height > 0) {
      RadianceTerms terms;
      terms.sun_disc = state_.sun_disc;
      terms.ground = state_.ground;
      // Auto-exposure meters the frame as `atmo render` meters its PNG (AutoExposureEv100's
      // statistic of the linear sRGB image), on the GPU with 8 bytes read back a frame or two
      // later (gl::ExposureMeter), every 16 frames and whenever the sky changed (which waits for
      // its reading, as does the last frame of a --frames run, so that a new sky is never shown
      // at the last one's exposure).
      const bool meter = state_.auto_exposure && (frame_ % 16 == 0 || frame_ < 2 || !metered_) && sky_->HasFrame();
      // Hillaire alone in RGB, tone-mapped, not metered in this frame: its frame pass runs in the
      // display's fragment shader (DrawFused), no frame texture.
      // The night sky is added to the frame textures: not with the fused pass.
      UpdateNight();
      const bool night = NightShown();
      const gl::HillaireGl* fused =
          compare_sky_ == nullptr && !false_colour_ && !meter && !night && sky_->batch_count() == 1
              ? sky_->hillaire_gl()
              : nullptr;
      // While the next sky's tables build on a thread of their own (source4d with
      // --source4d-tables cpu), the shown frame is drawn again only when what it depends on
      // changed: on llvmpipe the same frame again would take the cores from the build (1280x720:
      // a frame pass of ~90 ms on both cores, docs/viewer.md#source4d-tables-on-the-cpu).
      const Camera camera = ViewCamera(state_, width, height);
      const Camera& drawn = drawn_camera_;
      const bool frame_current =
          drawn_generation_ == sky_generation_ && !view_changed && camera.kind == drawn.kind &&
          camera.width == drawn.width && camera.height == drawn.height && camera.fov_deg == drawn.fov_deg &&
          camera.yaw_deg == drawn.yaw_deg && camera.pitch_deg == drawn.pitch_deg &&
          terms.sun_disc == drawn_terms_.sun_disc && terms.ground == drawn_terms_.ground && night == drawn_night_;
      const bool reuse_frame = frame_current && compare_sky_ == nullptr && pending_ != nullptr &&
                               pending_->BuildsOnItsOwnThread() && sky_->SameInputsSameFrame();
      waiting_for_build_ = reuse_frame;
      if (fused == nullptr && !reuse_frame) {
        const bool moon = night && moon_ != nullptr;
        if (moon) RenderMoonlit(*sky_, camera, terms, moon_frames_);
        GiveNight(*sky_);
        sky_->RenderFrame(camera, terms, pass_timings_);
        if (night) AddNight(*sky_, camera);
        if (moon) AddMoon(*sky_, camera, moon_frames_);
        drawn_generation_ = sky_generation_;
        drawn_camera_ = camera;
        drawn_terms_ = terms;
        drawn_night_ = night;
      }
      if (fused != nullptr) drawn_generation_ = -1;
      if (compare_sky_ != nullptr) {
        // The compared sky gets the night as the shown one, the moon where its channels are the
        // shown sky's (the moon's irradiance is per channel).
        const bool night_on_gpu = NightOnGpu(*compare_sky_);
        const bool moon = night_on_gpu && moon_ != nullptr && compare_sky_->batch_count() == sky_->batch_count();
        if (moon) RenderMoonlit(*compare_sky_, camera, terms, compare_moon_frames_);
        GiveNight(*compare_sky_);
        compare_sky_->RenderFrame(camera, terms, pass_timings_);
        if (night_on_gpu) AddNight(*compare_sky_, camera);
        if (moon) AddMoon(*compare_sky_, camera, compare_moon_frames_);
      }
      if (meter) {
        std::vector<const gl::GpuTexture*> frames;
        for (std::size_t b = 0; b < sky_->batch_count(); ++b) frames.push_back(&sky_->frame_texture(b));
        meter_->Meter(frames, weights_, camera.kind == CameraKind::kFisheye);
        // Relative units have no level to adapt to: the camera meter places them (as atmo render).
        const bool relative = plan_.unit == RadianceUnit::kRelative && current_.channel_count() == 3;
        metering_ = relative ? Metering::kCamera : ParseMetering(options_.render.metering);
      }
      if (state_.auto_exposure) {
        const bool wait = meter && (!metered_ || last_frame);
        if (const std::optional<gl::ExposureMeter::Reading> reading = meter_->Latest(wait)) {
          metered_ev100_ = reading->pixels > 0 ? MeteredEv100(reading->log2_average, metering_) : 0.0;
        }
        if (meter) metered_ = true;
      }
      mapping_.exposure = ExposureFromEv100(state_.auto_exposure ? metered_ev100_ : state_.ev100);
      if (fused != nullptr) {
        gl::GpuPassTimer timer(pass_timings_);
        display_->DrawFused(*fused, ToSharedCamera(ViewCamera(state_, width, height)), terms, weights_, mapping_,
                            width, height);
        timer.Stop("frame_and_display");
      } else {
        gl::GpuPassTimer timer(pass_timings_);
        DisplayPass::View view;
        view.mode = compare_sky_ != nullptr ? compare_view_ : 0;
        view.false_colour = false_colour_;
        view.split_column = static_cast<int>(std::lround(split_ * width));
        view.split_line = !options_.no_panels;
        display_->Draw(*sky_, compare_sky_.get(), view, weights_, mapping_, width, height);
        timer.Stop("display");
      }
      gl::GpuPassTimer timer(pass_timings_);
      ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
      timer.Stop("panels");
    }
    if (last_frame && !options_.window_screenshot.empty()) {
      WriteWindow(options_.window_screenshot, width, height, offscreen_ != nullptr);
    }
    {
      std::optional<ScopedPassTimer> timer;
      if (timed) timer.emplace(timings_, "swap");
      if (offscreen_ != nullptr) offscreen_->Present();
      else context_->SwapBuffers();
    }
    if (timed) timings_frame_ = frame_;
    // The frame time: from one swap to the next (the first frame compiles the shaders: left out).
    if (frame_ > 0) {
      frame_ms_sum += 1e3 * dt_s;
      ++timed_frames;
    }
    frame_ms_ = 1e3 * dt_s;
    if (frame_log_ != nullptr) {
      std::fprintf(frame_log_, "%d %.3f %s %s %.6f\n", frame_, frame_ms_, sky_ ? shown_model_.c_str() : "-",
                   pending_ ? pending_model_.c_str() : "-", pending_ ? pending_->progress() : 1.0);
    }
    if (last_frame) {
      ++frame_;
      break;
    }
  }
  ReadTimings(/*wait=*/true);
  if (!options_.save_config.empty()) {
    WriteConfig(options_.save_config, current_);
    std::printf("atmo-viewer: wrote %s\n", options_.save_config.c_str());
  }
  if (frames > 0) {
    const double mean_ms = timed_frames > 0 ? frame_ms_sum / timed_frames : 0.0;
    std::printf("atmo-viewer: %d frames of %s at %dx%d (%s%s), mean frame time %.2f ms (%.1f fps) over frames "
                "1..%d, on %s\n",
                frame_, shown_model_.c_str(), options_.render.width, options_.render.height,
                std::string(ToString(state_.camera)).c_str(),
                options_.recompute_every_frame ? ", every table every frame" : "", mean_ms,
                mean_ms > 0.0 ? 1000.0 / mean_ms : 0.0, frame_ - 1, context_->renderer().c_str());
    std::string passes;
    for (const PassTiming& pass : run_timings_.entries()) {
      passes += cli::Format("%s%s %.2f", passes.empty() ? "" : ", ", pass.name.c_str(), pass.total_ms / pass.calls);
    }
    std::printf("atmo-viewer: mean ms per frame that ran it: %s\n", passes.c_str());
    if (sky_ != nullptr && !sky_->Status().empty()) std::printf("atmo-viewer: %s\n", sky_->Status().c_str());
  }
  return 0;
}

}  // namespace

int RunViewer(const ViewerOptions& options) {
  if (!options.render.exr_path.empty()) cli::CheckOutputWritable(options.render.exr_path);
  if (!options.render.png_path.empty()) cli::CheckOutputWritable(options.render.png_path);
  if (!options.save_config.empty()) cli::CheckOutputWritable(options.save_config);
  if (!options.window_screenshot.empty()) {
    cli::CheckOutputWritable(options.window_screenshot);
    cli::CheckExtension("--window-screenshot", options.window_screenshot, ".png");
    if (options.frames == 0) throw Error("--window-screenshot needs --frames N: it writes the last frame");
  }
  cli::CheckExtension("--exr", options.render.exr_path, ".exr");
  cli::CheckExtension("--png", options.render.png_path, ".png");
  if (options.frames == 0 && (!options.render.exr_path.empty() || !options.render.png_path.empty())) {
    throw Error("--screenshot (or --exr, --png, -o) needs --frames N: it writes the last frame");
  }
  if (options.offscreen && options.frames == 0) {
    throw Error("--offscreen needs --frames N: without a window nothing would end the run");
  }
  if (options.offscreen && options.hidden) throw Error("--offscreen has no window to hide (drop --hidden)");
  Viewer viewer(options);
  return viewer.Run();
}

}  // namespace atmo::viewer
