// `atmo render --camera cubemap`: the environment outputs of a rendered cube map beyond the EXR
// and PNG strip that render writes itself: the KTX2 cubemap, the spherical harmonics (JSON), the
// irradiance cube map and the specular mip chain (docs/environment.md, docs/cli.md).
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "atmo/engine_target.h"
#include "atmo/cubemap.h"
#include "atmo/error.h"
#include "atmo/ibl.h"
#include "atmo/image.h"
#include "commands.h"

namespace atmo::cli {

namespace {

bool HasExrExtension(const std::string& path) {
  return path.size() >= 4 && (path.compare(path.size() - 4, 4, ".exr") == 0 || path.compare(path.size() - 4, 4, ".EXR") == 0);
}

// A level and its smaller copies down to 1 texel (or `count` levels).
std::vector<Cubemap> MipChain(const Cubemap& base, int count) {
  std::vector<Cubemap> chain = {base};
  while (static_cast<int>(chain.size()) < count && chain.back().face_size > 1) {
    chain.push_back(DownsampleCubemap(chain.back()));
  }
  return chain;
}

nlohmann::json Vec(const glm::dvec3& v) { return nlohmann::json::array({v.x, v.y, v.z}); }

nlohmann::json ShFrameJson(const SphericalHarmonics& sh, const char* axes, const glm::dvec3& up) {
  nlohmann::json radiance = nlohmann::json::array();
  nlohmann::json irradiance = nlohmann::json::array();
  const std::array<glm::dvec3, 9> e = ShIrradianceCoefficients(sh);
  for (int k = 0; k < 9; ++k) {
    radiance.push_back(Vec(sh.radiance[k]));
    irradiance.push_back(Vec(e[k]));
  }
  return {{"axes", axes},
          {"radiance_coefficients", radiance},
          {"irradiance_coefficients", irradiance},
          {"irradiance_up", Vec(ShIrradiance(sh, up))}};
}

void WriteText(const std::string& path, const std::string& text) {
  WriteFileAtomically(path, [&](const std::filesystem::path& temporary) {
    std::ofstream stream(temporary, std::ios::trunc);
    if (!stream) throw std::runtime_error("cannot create '" + temporary.string() + "'");
    stream << text;
    stream.close();
    if (!stream) throw std::runtime_error("error while writing '" + temporary.string() + "'");
  });
}

}  // namespace

bool WantsEnvironmentOutputs(const RenderCommand& command) {
  return !command.ktx2_path.empty() || !command.sh_path.empty() || !command.irradiance_path.empty() ||
         !command.specular_path.empty() || !command.hdr_faces.empty();
}

std::vector<std::string> HdrFacePaths(const std::string& name) {
  std::vector<std::string> paths;
  if (name.empty()) return paths;
  for (const char* face : {"px", "nx", "py", "ny", "pz", "nz"}) paths.push_back(name + "_" + face + ".hdr");
  return paths;
}

void WriteEnvironmentOutputs(const RenderCommand& command, const Cubemap& cube, const std::string& unit_description,
                             bool luminance, std::vector<std::string>& written) {
  if (cube.channels() != 3) {
    throw Error("--ktx2, --sh, --irradiance, --specular and --hdr-faces need 3 colour channels (use --unit luminance)");
  }
  const std::string writer = std::string("atmo ") + ATMO_VERSION;
  if (!command.hdr_faces.empty()) {
    const Cubemap faces = command.target == "three" ? CubeTextureForThree(cube) : cube;
    const std::vector<std::string> paths = HdrFacePaths(command.hdr_faces);
    for (int f = 0; f < kCubeFaceCount; ++f) {
      WriteRadianceHdr(paths[f], faces.faces[f]);
      written.push_back(paths[f]);
    }
  }
  if (!command.ktx2_path.empty()) {
    const std::vector<Cubemap> chain = MipChain(cube, command.mips ? 64 : 1);
    WriteKtx2(command.ktx2_path, chain, command.ktx2_float32, writer);
    written.push_back(command.ktx2_path);
  }
  if (!command.sh_path.empty()) {
    const SphericalHarmonics enu = ProjectSphericalHarmonics(cube, ShFrame::kEnu);
    const SphericalHarmonics cube_frame = ProjectSphericalHarmonics(cube, ShFrame::kCube);
    nlohmann::json j = {
        {"format", "atmo L2 spherical harmonics of sky radiance"},
        {"basis",
         "real, orthonormal; order (l,m) = (0,0) (1,-1) (1,0) (1,1) (2,-2) (2,-1) (2,0) (2,1) (2,2); "
         "Y00 = 0.282095, Y1-1 = 0.488603 y, Y10 = 0.488603 z, Y11 = 0.488603 x, Y2-2 = 1.092548 xy, "
         "Y2-1 = 1.092548 yz, Y20 = 0.315392 (3z^2 - 1), Y21 = 1.092548 xz, Y22 = 0.546274 (x^2 - y^2) "
         "(Ramamoorthi & Hanrahan 2001, no Condon-Shortley phase)"},
        {"radiance_coefficients", "L_lm = integral of L(w) Y_lm(w) dOmega (coefficients of radiance)"},
        {"irradiance_coefficients",
         "E_lm = A_l L_lm with A_0 = pi, A_1 = 2 pi / 3, A_2 = pi / 4; E(n) = sum E_lm Y_lm(n) = integral of "
         "L max(n.w, 0) dOmega in the L2 approximation"},
        {"colour", luminance ? "linear Rec.709/sRGB (D65)" : "the model's channels"},
        {"radiance_unit", unit_description},
        {"irradiance_unit", luminance ? "lux (lm m^-2) for the luminance 0.2126 R + 0.7152 G + 0.0722 B"
                                      : "the radiance unit times sr"},
        {"sun_disc", !command.no_sun_disc},
        {"cube_face_size", cube.face_size},
        {"enu", ShFrameJson(enu, "x east, y north, z up (atmo)", {0.0, 0.0, 1.0})},
        {"y_up", ShFrameJson(cube_frame, "X east, Y up, Z south (glTF/OpenGL world; -Z north)", {0.0, 1.0, 0.0})},
    };
    if (luminance) {
      const glm::dvec3 e = ShIrradiance(enu, {0.0, 0.0, 1.0});
      j["horizontal_illuminance_lux"] = Luminance(e.x, e.y, e.z);
    }
    WriteText(command.sh_path, j.dump(2) + "\n");
    written.push_back(command.sh_path);
  }
  if (!command.irradiance_path.empty()) {
    Cubemap irradiance = IrradianceCubemap(cube, command.irradiance_size);
    if (HasExrExtension(command.irradiance_path)) {
      WriteExr(command.irradiance_path, CubemapExrImage(irradiance),
               {{"atmo:content", "irradiance E(n) = integral of L max(n.w, 0) dOmega"},
                {"atmo:cubeFrame", "X east, Y up, Z south"}});
    } else {
      WriteKtx2(command.irradiance_path, std::span<const Cubemap>(&irradiance, 1), command.ktx2_float32, writer);
    }
    written.push_back(command.irradiance_path);
  }
  if (!command.specular_path.empty()) {
    SpecularSettings settings;
    settings.levels = command.specular_levels;
    settings.samples = command.specular_samples;
    const std::vector<Cubemap> chain = PrefilterSpecular(cube, settings);
    WriteKtx2(command.specular_path, chain, command.ktx2_float32, writer);
    written.push_back(command.specular_path);
  }
}

}  // namespace atmo::cli
