// The night sky's own light: the airglow of the upper atmosphere and the zodiacal light, attenuated
// by the atmosphere in front of them (docs/night.md). No sky model scatters it from the sun, so the
// renderers add it to the model's radiance as they add the sun disc: RenderView, RenderViewFolded
// and the cube maps through RadianceTerms::night_sky, the GL renderers after read-back, and
// atmo::ComputeIlluminance in its own column.
//
// To use it:
//   const atmo::NightSky night(parameters, /*altitude_m=*/0.0, sun_direction);   // ecliptic: default
//   std::vector<double> L(parameters.channel_count());
//   night.Radiance(view, L);            // sr^-1 per unit solar irradiance, like SkyView::Radiance
//   atmo::RadianceTerms terms;
//   terms.night_sky = &night;           // RenderView adds it to every pixel
//
// Units. Like every model's radiance, per unit solar irradiance at the top of the atmosphere and per
// channel: a channel's value times the solar spectrum at its wavelength is the spectral radiance
// (atmo::SpectralConversion). The airglow's line spectrum is projected onto the channels so that
// its CIE XYZ (and so its luminance) is exact whatever the channel count; the zodiacal light has
// the sun's spectrum (Leinert et al. 1998, section 8, to first order), which is the same value in
// every channel.
//
// Geometry. The airglow is a spherical shell of uniform emission (NightSkySettings): a ray picks up
// the emission along its length inside the shell, which brightens the sky towards the horizon (the
// van Rhijn effect) without the thin-layer formula's singularity at the limb seen from space. The
// emission a ray meets after it has passed below the shell (all of it, for an observer below the
// shell) is attenuated by the ray's transmittance to the top of the atmosphere; what it meets
// before (an observer in space, looking through the shell) is not, the air above the shell being
// negligible. The zodiacal light comes from outside the atmosphere: attenuated by the
// transmittance, 0 on rays that meet the ground. What scatters out of these rays is not scattered
// back in by this class (the direct, attenuated light only). The reference path tracer adds the
// same direct term and traces the airglow's scattered light with paths of its own
// (atmo::RenderProgressive); the deterministic models leave it out (docs/night.md).
#pragma once

#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "atmo/parameters.h"
#include "atmo/stars.h"

namespace atmo {

// The ecliptic's north pole in the observer's frame (x east, y north, z up) when neither a date nor
// a place gives it: the pole as high as it can be at right angles to the sun, so that the ecliptic
// runs through the sun as low as a great circle can. The zenith is then at ecliptic latitude
// 90 degrees minus the sun's depression, where the zodiacal light is faintest: the condition of the
// published dark-sky measurements (docs/night.md). With a date and a place
// (EclipticPoleDirection) the zodiacal light is where it is that night.
glm::dvec3 DefaultEclipticPole(const glm::dvec3& sun_direction);

// The ecliptic's north pole (of date: mean obliquity, equinox of date) in the local frame of an
// observer at `latitude_deg`, `longitude_deg` (east +) at `julian_day_utc`. Throws atmo::Error as
// ComputeSunPosition does for bad input.
glm::dvec3 EclipticPoleDirection(double julian_day_utc, double latitude_deg, double longitude_deg);

// Brings a linear Rec.709 colour with a negative component into the gamut by mixing it with the
// grey of the same luminance (Y = 0.2126 R + 0.7152 G + 0.0722 B kept), just enough that the lowest
// component is 0; a colour of luminance <= 0 becomes black.
void ClipToGamut(float* rgb);

class NightSky {
 public:
  // Entries of the per-angle tables (Folded::airglow, Folded::transmitted), uniform in the cosine
  // of the view zenith angle over [-1, 1].
  static constexpr int kAngleSamples = 4097;
  // The zodiacal light's lookup (Leinert et al. 1998, Table 17, resampled): kZodiacalSinBeta rows
  // uniform in |sin(ecliptic latitude)| over [0, 1], each of kZodiacalCosElongation values uniform
  // in cos(elongation from the sun) over [-1, 1], read bilinearly; in units of Table 17.
  static constexpr int kZodiacalSinBeta = 129;
  static constexpr int kZodiacalCosElongation = 513;
  static std::span<const float> ZodiacalGrid();

  // The night sky seen from `altitude_m` with the sun along `sun_direction` (unit); the ecliptic's
  // north pole `ecliptic_pole` (unit, at right angles to the sun; a zero vector: DefaultEclipticPole).
  // Precomputes the transmittance and the airglow path per view zenith angle (1.4 ms for 3
  // channels, 9.7 ms for 15 on 2 cores: BM_NightSkyTables). Radiance is 0 when parameters.night_sky.enabled is false (the stars of SetStars
  // remain), and the whole night sky, stars included, is inactive for a half-space. Throws
  // atmo::Error for a non-finite or negative altitude or a non-unit direction.
  NightSky(const AtmosphereParameters& parameters, double altitude_m, const glm::dvec3& sun_direction,
           const glm::dvec3& ecliptic_pole = glm::dvec3(0.0));

  // Places the sky by `frame` (the ecliptic, and the Milky Way of the integrated starlight); the
  // constructor's is CelestialFrame::FromSun. SetStars sets it too.
  void SetFrame(const CelestialFrame& frame);
  // Adds the stars of `catalogue` (kept by reference: it must outlive this) placed by `frame`, and
  // takes the ecliptic from the frame. The renderers then share each star's irradiance
  // (StarRelativeIrradiance) times the transmittance bilinearly among the 2 x 2 pixels around its
  // direction, each share over its pixel's solid angle: its energy is right at any resolution.
  void SetStars(const StarCatalogue& catalogue, const CelestialFrame& frame);
  const StarCatalogue* stars() const { return stars_; }
  const CelestialFrame& frame() const { return frame_; }
  // Per star of the catalogue: its irradiance over the sun's per channel (star-major).
  const std::vector<double>& star_irradiance() const { return star_irradiance_; }
  // The transmittance to the top of the atmosphere along a view of zenith cosine `mu` (0 on the
  // ground), per channel, from the tables.
  void Transmittance(double mu, std::span<double> out) const;

  bool active() const { return active_; }
  const glm::dvec3& sun_direction() const { return sun_direction_; }
  // Whether the zodiacal light is there (its scale > 0 and the glow on), and its relative radiance
  // per unit of the zodiacal grid.
  bool zodiacal() const { return zodiacal_relative_ > 0.0; }
  double zodiacal_relative() const { return zodiacal_relative_; }
  bool glow() const { return active_ && glow_; }
  std::size_t channel_count() const { return channel_count_; }
  const glm::dvec3& ecliptic_pole() const { return ecliptic_pole_; }

  // Airglow, zodiacal light and integrated starlight along `view` (unit), per channel, into `out`
  // (channel_count()).
  void Radiance(const glm::dvec3& view, std::span<double> out) const;
  void AirglowRadiance(const glm::dvec3& view, std::span<double> out) const;
  void ZodiacalRadiance(const glm::dvec3& view, std::span<double> out) const;
  // The integrated starlight (Leinert et al. 1998, Table 35: the stars fainter than about V 6.5 and
  // the diffuse galactic light, less the catalogue's stars fainter than V 6.5 that SetStars draws),
  // attenuated: solar-coloured, so the same relative value in every channel times the transmittance.
  void StarlightRadiance(const glm::dvec3& view, std::span<double> out) const;
  // Its value outside the atmosphere along `view` (relative radiance, per unit solar irradiance):
  // the local grid (starlight_grid) read bilinearly.
  double StarlightValue(const glm::dvec3& view) const;
  // Table 35 at galactic longitude and latitude (degrees), in S10(sun), before the catalogue's stars
  // are taken out; the 28 unmapped cells interpolated along their latitude.
  static double StarlightS10(double longitude_deg, double latitude_deg);
  // The starlight resampled on the local frame, for the renderers' per-pixel pass (no
  // trigonometry per pixel): two kStarlightSide x kStarlightSide grids, the upper hemisphere
  // (z >= 0) then the lower, each a hemi-octahedral map. A direction v maps to u = v.x / n,
  // w = v.y / n with n = |v.x| + |v.y| + |v.z|, and to the grid coordinates s = u + w, t = u - w
  // in [-1, 1] (column (s + 1) (side - 1) / 2, row (t + 1) (side - 1) / 2), read bilinearly; the
  // two maps meet on the horizon. About 1.4 degrees per cell there; relative radiance outside the
  // atmosphere.
  static constexpr int kStarlightSide = 65;
  const std::vector<float>& starlight_grid() const { return starlight_grid_; }
  bool starlight() const { return !starlight_grid_.empty(); }

  // The airglow's radiance per channel at the top of the atmosphere looking down the zenith of the
  // shell, unattenuated (the channels' projection of the ESO spectrum times airglow_scale).
  const std::vector<double>& airglow_zenith() const { return airglow_zenith_; }
  // The zodiacal light's brightness at 500 nm in W m^-2 sr^-1 nm^-1 along `view`, outside the
  // atmosphere (Leinert et al. 1998, Table 17, times zodiacal_scale).
  double ZodiacalBrightness500(const glm::dvec3& view) const;

  // Adds sum_c weights[c][k] L_c(view) to out[m i + k] for every direction i (m = weights' width,
  // 1 to 3 for vec3 weights, `outputs`): the per-pixel pass of the renderers. The weights are folded
  // into the tables once (Fold), so a pixel costs the same for 3 or 40 channels. Directions of
  // length 0 are skipped.
  class Folded {
   public:
    void Add(std::span<const glm::dvec3> views, std::span<float> out) const;
    int outputs() const { return outputs_; }
    const NightSky* night() const { return night_; }
    // The fold: output k of channel c is weights()[c * outputs() + k].
    const std::vector<float>& weights() const { return weights_; }
    // The per-angle tables (kAngleSamples x outputs(); empty when the night sky is inactive): the
    // attenuated airglow, and the folded transmittance. A pixel adds, at
    // x = (mu + 1) (kAngleSamples - 1) / 2, a = min(floor(x), kAngleSamples - 2), f = x - a:
    // (1 - f) (airglow[a] + z transmitted[a]) + f (airglow[a + 1] + z transmitted[a + 1]), z the
    // light from outside the atmosphere: zodiacal_relative() times the zodiacal grid's value plus
    // StarlightValue.
    const std::vector<float>& airglow() const { return airglow_; }
    const std::vector<float>& transmitted() const { return transmitted_; }
    // The stars above the horizon as the renderers add them: each star's direction (local frame)
    // and its outputs() values (its irradiance over the sun's times the transmittance, folded;
    // brought into the gamut with 3 outputs), star-major. Empty without stars.
    void Stars(std::vector<glm::dvec3>& directions, std::vector<float>& values) const;

   private:
    friend class NightSky;
    const NightSky* night_ = nullptr;
    int outputs_ = 0;
    std::vector<float> airglow_;   // [angle][output]
    std::vector<float> transmitted_;  // [angle][output]: sum_c w_ck T_c, times the zodiacal light
    std::vector<float> weights_;      // [channel][output]
  };
  // `weights` has channel_count() entries; `outputs` of their components are used (1..3). With 3
  // outputs (linear sRGB), a colour outside the gamut (the airglow's orange lines seen through
  // much air give a negative blue) is brought in by ClipToGamut.
  Folded Fold(std::span<const glm::vec3> weights, int outputs) const;
  // The same with weights[c] = scale[c] in output c (outputs = channel count, up to any number):
  // the unfolded image of RenderView, each channel times its solar irradiance.
  Folded Scaled(std::span<const double> scale) const;

 private:
  // Index and fraction of the view zenith angle in the per-angle tables.
  void Locate(double mu, int& index, double& fraction) const;
  double ZodiacalTableValue(const glm::dvec3& view) const;

  bool active_ = false;
  bool glow_ = false;  // the airglow and zodiacal light (NightSkySettings::enabled)
  std::size_t channel_count_ = 0;
  glm::dvec3 sun_direction_{0.0, 0.0, 1.0};
  glm::dvec3 ecliptic_pole_{1.0, 0.0, 0.0};
  std::vector<double> airglow_zenith_;
  double zodiacal_relative_ = 0.0;  // per unit of Table 17: relative radiance (grey)
  double starlight_relative_ = 0.0;  // per S10(sun): relative radiance (grey); 0 without
  std::vector<float> starlight_grid_;  // 2 x kStarlightSide^2 (StarlightValue), relative radiance
  void BuildStarlight();  // starlight_grid_ for frame_ and stars_
  // Per view zenith angle (kAngles samples, uniform in angle over [0, pi]) and channel.
  std::vector<double> airglow_path_;  // [angle][channel]: attenuated airglow, per unit zenith brightness
  std::vector<double> transmittance_;  // [angle][channel]: to the top of the atmosphere; 0 on the ground
  const StarCatalogue* stars_ = nullptr;
  CelestialFrame frame_;
  std::vector<double> star_irradiance_;
  std::vector<double> wavelengths_nm_;
};

}  // namespace atmo
