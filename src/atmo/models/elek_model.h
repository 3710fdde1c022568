// Model `elek`: the precomputed scattering table of the Atmosphere Plus seed
// (000_3697ee745cef898b.txt, after Elek 2009), as docs/models/elek.md describes.
//
// One 3D table I(h, cos phi, cos delta) (altitude, view zenith, sun zenith) holds the factored
// Rayleigh scattering per channel (RGB) and the factored Mie scattering of the first channel
// (alpha), summed over K orders; Radiance() returns p_R(nu) I_R + p_M(nu) I_M with nu = cos(view,
// sun), per unit solar irradiance. Options (`--option key=value`):
//   size=32x256x32         W x H x D of the table (each >= 2; the seed's 32x128x32, 32x64x32 work)
//   mapping=nonlinear      nonlinear (the seed's sqrt / cube-root mapping) or linear
//   orders=4               K, the number of scattering orders (1..16)
//   samples=30             N, trapezoidal steps per ray (the seed's 30)
//   steps=quadratic        quadratic (t = t_max (i/N)^2) or uniform step sizes
//   rayleigh_phase=parameters  parameters, rayleigh or modified (the seed's modified Rayleigh)
//   gather=seed            seed: the gather reads the factored I (no phase of the first order);
//                          phase: the first gather restores single scattering's own phase 4 pi p(nu_w)
//   coupling=separate      separate: Rayleigh gathers Rayleigh, Mie gathers Mie (the seed);
//                          total: both gather the light of both
//   mie=alpha              alpha: Mie of the first channel, the others by Bruneton's ratio (the
//                          seed's RGBA table); rgb: Mie per channel (for measurement)
//   gather_rows=64         view-zenith rows of the gather tables
//   gather_points=4        Gauss-Legendre points per row interval of the gather matrix
//   gather_azimuths=64     azimuth intervals on [0, pi] of the numerical azimuth integrals
//   transmittance_lut=256x64, transmittance_samples=40   the 2D transmittance table (sun rays)
//   table=NAME             load NAME.json/NAME.raw written by `atmo precompute` instead of computing
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "atmo/model.h"
#include "cpu/elek_tables.h"
#include "shared/shared.h"

namespace atmo {

struct ElekSettings {
  glm::ivec3 size{32, 256, 32};
  int mapping = shared::kElekMappingNonLinear;
  int orders = 4;
  int samples = 30;
  int steps = shared::kElekStepsQuadratic;
  std::string rayleigh_phase = "parameters";  // parameters | rayleigh | modified
  bool phase_gather = false;                  // gather=phase
  bool coupled = false;                       // coupling=total
  bool mie_per_channel = false;               // mie=rgb
  // The Lambertian ground feeding the next order (elek.glsl, "The ground"): auto | on | off; auto
  // is on when any channel's albedo is above 0.
  std::string ground = "auto";
  int gather_rows = 64;
  int gather_points = 4;
  int gather_azimuths = 64;
  glm::ivec2 transmittance_lut{256, 64};
  int transmittance_samples = 40;
  std::string table;  // load instead of computing

  // Throws atmo::Error for an unknown key or a value out of range.
  static ElekSettings FromOptions(const ModelOptions& options);
  // The settings that define the table's content, as "key=value" pairs in a fixed order (written
  // into exported manifests and compared on load).
  std::vector<std::pair<std::string, std::string>> TableOptions() const;
  // Whether the ground term is computed for these parameters (off where every albedo is 0: it
  // would add nothing).
  bool UsesGround(const AtmosphereParameters& parameters) const;
};

class ElekModel final : public Model {
 public:
  ElekModel(const AtmosphereParameters& parameters, const ElekSettings& settings);

  std::string_view name() const override { return "elek"; }
  void Precompute() override;
  double EstimatedPrecomputeSeconds() const override;
  std::unique_ptr<SkyView> View(double altitude_m, const glm::dvec3& sun_direction) const override;

  // The tables of one batch of three channels.
  struct Batch {
    shared::AtmosphereParameters atmosphere;
    shared::Texture2D transmittance;
    std::vector<cpu::ElekScattering> orders;  // I^(1) .. I^(K), per channel; empty for a loaded table
    cpu::ElekScattering total;                // sum over the orders (loaded: Mie of channel 0 in all three)
  };
  const std::vector<Batch>& batches() const { return batches_; }
  const ElekSettings& settings() const { return settings_; }
  cpu::ElekGrid grid() const;

  // Radiance of one batch (its three channels) from the table, for an observer at radius r.
  shared::vec3 BatchRadiance(const Batch& batch, double r, double mu, double mu_s, double nu) const;

  // The RGBA table of a batch in the seed's index layout i = x + y W + z W H, 4 floats per texel.
  std::vector<float> Rgba(std::size_t batch) const;
  // Replaces the batch's summed table by an RGBA one (a loaded table; its orders are dropped).
  void SetRgba(std::size_t batch, const std::vector<float>& rgba);
  // Sets the tables of a batch computed elsewhere (the GL backend, gl/elek_gl.h) instead of by
  // Precompute(): the transmittance table, the orders I^(1) .. I^(K) and their sum, each with the
  // sizes of the settings. Throws atmo::Error for other sizes or for a model that loads its table
  // (option table=NAME).
  void SetComputedTables(std::size_t batch, shared::Texture2D transmittance, std::vector<cpu::ElekScattering> orders,
                         cpu::ElekScattering total);

 protected:
  // The table cache (include/atmo/table_cache.h): each batch's transmittance table and summed
  // table. Read back, a batch has no orders (as a loaded table); a model that loads its table
  // (option table=NAME) keeps nothing.
  bool SaveTables(std::vector<unsigned char>& bytes) const override;
  bool LoadTables(std::span<const unsigned char> bytes) override;

 private:
  void ComputeTables(Batch& batch) const;

  ElekSettings settings_;
  std::vector<Batch> batches_;
};

}  // namespace atmo
