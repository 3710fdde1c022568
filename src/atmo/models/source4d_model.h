// Model `source4d`: exact single scattering along each view ray plus a 4D table of the
// phase-weighted incident radiance of orders >= 2, built order by order by gathering
// (shared/source4d.glsl, cpu/source4d_tables.h; docs/models/source4d.md).
//
// Options (`--option key=value`):
//   table=16x24x48x8       r layers x view zeniths x sun zeniths x azimuths of the 4D table
//   gather=97x9            zenith x azimuth nodes of the incident-direction grid (each 3..512;
//                          at most 2^26 gathering rays: r layers x sun zeniths x directions)
//   gather_samples=24      steps of each gathering ray (2..1000)
//   orders=5               orders computed explicitly (2..32); a geometric tail adds the rest;
//                          1: single scattering alone (for validation)
//   tail=on                on | off: the geometric tail after the last order
//   samples=64             steps of the per-view ray march (split at the shadow's edges)
//   transmittance_lut=256x64, transmittance_samples=200   the 2D transmittance table
//   sky_view=auto          inside the atmosphere, a sky-view table per observer and sun (the rays
//                          of sky.glsl's mapping, marched with `samples` steps each): auto: images
//                          (RadianceBatch) read it, made on their first use, and single queries
//                          march their direction; on: every query reads it; off: none
//   sky_view_lut=384x216   its azimuths (over 360 degrees; even) x rows (even: sky and ground
//                          halves)
#pragma once

#include <memory>
#include <mutex>
#include <vector>

#include "atmo/model.h"
#include "cpu/source4d_tables.h"
#include "shared/shared.h"

namespace atmo {

// The precomputation's cost of each batch of three channels after the first, relative to the
// first's (EstimatedPrecomputeSeconds).
inline constexpr double kSource4dExtraBatchCost = 0.7;

struct Source4dModelSettings {
  cpu::Source4dSettings tables;
  int samples = 64;
  enum class SkyViewMode { kAuto, kOn, kOff };
  SkyViewMode sky_view = SkyViewMode::kAuto;
  glm::ivec2 sky_view_lut{384, 216};
  // Throws atmo::Error for an unknown key or a value out of range.
  static Source4dModelSettings FromOptions(const ModelOptions& options);
};

class Source4dModel final : public Model {
 public:
  Source4dModel(const AtmosphereParameters& parameters, const Source4dModelSettings& settings);

  std::string_view name() const override { return "source4d"; }
  void Precompute() override;
  double EstimatedPrecomputeSeconds() const override;
  std::unique_ptr<SkyView> View(double altitude_m, const glm::dvec3& sun_direction) const override;

  struct Batch {
    shared::AtmosphereParameters atmosphere;
    cpu::Source4dTables tables;
  };
  const std::vector<Batch>& batches() const { return batches_; }
  const Source4dModelSettings& settings() const { return settings_; }
  // Replaces batch `batch`'s tables with ones computed elsewhere (the GL backend's,
  // gl/source4d_gl.h), instead of Precompute. Throws atmo::Error when their sizes are not the
  // settings'.
  void SetComputedTables(std::size_t batch, cpu::Source4dTables tables);
  // How many texels of `view`'s sky-view table have been marched (0 for a view of another
  // model): the table's texels are marched as lookups first need them (for tests).
  static std::size_t SkyViewTexelsMarched(const SkyView& view);

 protected:
  // The table cache (include/atmo/table_cache.h): every batch's tables.
  bool SaveTables(std::vector<unsigned char>& bytes) const override;
  bool LoadTables(std::span<const unsigned char> bytes) override;

 private:
  Source4dModelSettings settings_;
  std::vector<Batch> batches_;
};

}  // namespace atmo
