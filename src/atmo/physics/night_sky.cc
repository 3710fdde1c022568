// The night sky's own light: airglow and zodiacal light (include/atmo/night_sky.h, docs/night.md).
#include "atmo/night_sky.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include <glm/gtc/matrix_inverse.hpp>
#include <oneapi/tbb/parallel_for.h>

#include "atmo/colour.h"
#include "atmo/error.h"
#include "atmo/gas_absorption.h"
#include "atmo/spectrum.h"
#include "physics/data/airglow_table.h"
#include "physics/data/starlight_table.h"
#include "physics/data/zodiacal_light_table.h"
#include "physics/shared_parameters.h"
#include "shared/shared.h"

namespace atmo {
namespace {

constexpr double kPi = std::numbers::pi;
// Entries of the per-angle tables, uniform in the cosine mu of the view zenith angle over [-1, 1]
// (a lookup without acos): 0.028 degrees apart at the horizon, where the attenuated airglow
// changes fastest, 1.8 degrees at the zenith, where it is flat.
constexpr int kAngles = NightSky::kAngleSamples;
// Trapezoid intervals of the transmittance quadrature (shared/transmittance.glsl: 40 err by at
// most 2.5e-3).
constexpr int kTransmittanceIntervals = 64;

// The airglow table's spectral radiance at `nm` (W m^-2 sr^-1 nm^-1), 0 outside it.
double AirglowSpectralRadiance(int bin) { return data::kAirglowZenith[bin] * 1e-9; }
double AirglowBinNm(int bin) { return data::kAirglowFirstNm + bin; }

// The airglow per channel (relative: per unit solar irradiance) whose CIE XYZ equals the table's.
// Start from each channel's band mean over the solar spectrum at its wavelength, then add the
// smallest correction (least squares in the channels) that makes XYZ exact: with 3 channels that is
// the solution of the 3 x 3 system, with many it barely moves the band means.
std::vector<double> ProjectAirglow(std::span<const double> wavelengths_nm) {
  const std::size_t n = wavelengths_nm.size();
  const SpectralConversion convert(wavelengths_nm);
  glm::dvec3 target(0.0);
  for (int i = 0; i < data::kAirglowCount; ++i) {
    target += AirglowSpectralRadiance(i) * CieColourMatching(AirglowBinNm(i));  // 1 nm bins
  }
  // Bands halfway to the neighbours in wavelength order (the presets list theirs from red to blue).
  std::vector<std::size_t> order(n);
  for (std::size_t c = 0; c < n; ++c) order[c] = c;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return wavelengths_nm[a] < wavelengths_nm[b]; });
  std::vector<double> sorted(n);
  for (std::size_t i = 0; i < n; ++i) sorted[i] = wavelengths_nm[order[i]];
  const std::vector<WavelengthBand> sorted_bands = ChannelBands(sorted);
  std::vector<WavelengthBand> bands(n);
  for (std::size_t i = 0; i < n; ++i) bands[order[i]] = sorted_bands[i];
  std::vector<double> g(n, 0.0);
  for (std::size_t c = 0; c < n; ++c) {
    double sum = 0.0;
    int count = 0;
    for (int i = 0; i < data::kAirglowCount; ++i) {
      const double nm = AirglowBinNm(i);
      if (nm >= bands[c].lower_nm && nm < bands[c].upper_nm) {
        sum += AirglowSpectralRadiance(i);
        ++count;
      }
    }
    const double mean = count > 0 ? sum / count
                                  : AirglowSpectralRadiance(std::clamp(
                                        static_cast<int>(std::lround(wavelengths_nm[c] - data::kAirglowFirstNm)), 0,
                                        data::kAirglowCount - 1));
    g[c] = mean / convert.solar_irradiance()[c];
  }
  const std::vector<glm::dvec3>& w = convert.xyz_weights();
  glm::dvec3 current(0.0);
  glm::dmat3 gram(0.0);  // W W^T
  for (std::size_t c = 0; c < n; ++c) {
    current += w[c] * g[c];
    gram += glm::outerProduct(w[c], w[c]);
  }
  if (std::abs(glm::determinant(gram)) > 0.0) {
    const glm::dvec3 lambda = glm::inverse(gram) * (target - current);
    for (std::size_t c = 0; c < n; ++c) g[c] += glm::dot(w[c], lambda);
  }
  return g;
}

// Length of the part of [0, t_end] along the ray from radius r at zenith cosine mu that lies inside
// the sphere of radius rho, split at t_split: (before, after).
std::array<double, 2> LengthInsideSphere(double r, double mu, double rho, double t_end, double t_split) {
  const double discriminant = r * r * (mu * mu - 1.0) + rho * rho;
  if (discriminant <= 0.0) return {0.0, 0.0};
  const double root = std::sqrt(discriminant);
  const double t0 = std::max(-r * mu - root, 0.0);
  const double t1 = std::min(-r * mu + root, t_end);
  if (t1 <= t0) return {0.0, 0.0};
  const double before = std::max(0.0, std::min(t1, t_split) - t0);
  const double after = std::max(0.0, t1 - std::max(t0, t_split));
  return {before, after};
}

// The zodiacal light resampled on a 1-degree grid of |lambda - lambda_sun| (0..180) and |beta|
// (0..90), bilinear between Table 17's entries; the cells without a measurement near the sun take
// the nearest measured value of their latitude column.
struct ZodiacalGrid {
  std::array<std::array<double, 91>, 181> value{};
  ZodiacalGrid() {
    double table[data::kZodiacalLongitudeCount][data::kZodiacalLatitudeCount];
    for (int b = 0; b < data::kZodiacalLatitudeCount; ++b) {
      int first = 0;
      while (data::kZodiacalLight500[first][b] <= 0.0) ++first;
      for (int l = 0; l < data::kZodiacalLongitudeCount; ++l) {
        table[l][b] = data::kZodiacalLight500[std::max(l, first)][b];
      }
    }
    const auto locate = [](const double* grid, int count, double x, int& i, double& f) {
      i = 0;
      while (i + 2 < count && x > grid[i + 1]) ++i;
      f = std::clamp((x - grid[i]) / (grid[i + 1] - grid[i]), 0.0, 1.0);
    };
    for (int lon = 0; lon <= 180; ++lon) {
      int i;
      double fi;
      locate(data::kZodiacalLongitudeDeg, data::kZodiacalLongitudeCount, lon, i, fi);
      for (int lat = 0; lat <= 90; ++lat) {
        int j;
        double fj;
        locate(data::kZodiacalLatitudeDeg, data::kZodiacalLatitudeCount, lat, j, fj);
        value[lon][lat] = (1 - fi) * ((1 - fj) * table[i][j] + fj * table[i][j + 1]) +
                          fi * ((1 - fj) * table[i + 1][j] + fj * table[i + 1][j + 1]);
      }
    }
  }
  // Bilinear on the 1-degree grid.
  double At(double lon_deg, double lat_deg) const {
    const double x = std::clamp(lon_deg, 0.0, 180.0);
    const double y = std::clamp(lat_deg, 0.0, 90.0);
    const int i = std::min(static_cast<int>(x), 179);
    const int j = std::min(static_cast<int>(y), 89);
    const double fx = x - i;
    const double fy = y - j;
    return (1 - fx) * ((1 - fy) * value[i][j] + fy * value[i][j + 1]) +
           fx * ((1 - fy) * value[i + 1][j] + fy * value[i + 1][j + 1]);
  }
};

const ZodiacalGrid& Zodiacal() {
  static const ZodiacalGrid grid;
  return grid;
}

// The same resampled on |sin beta| in [0, 1] and cos(elongation) in [-1, 1], the two dot products
// of a view with the ecliptic's pole and the sun, so that a pixel needs no inverse trigonometry:
// cos(elongation) = cos(beta) cos(lambda - lambda_sun).
struct ZodiacalDotGrid {
  static constexpr int kSin = NightSky::kZodiacalSinBeta;
  static constexpr int kCos = NightSky::kZodiacalCosElongation;
  std::vector<float> value = std::vector<float>(static_cast<std::size_t>(kSin) * kCos);
  ZodiacalDotGrid() {
    const ZodiacalGrid& grid = Zodiacal();
    for (int i = 0; i < kSin; ++i) {
      const double sin_beta = static_cast<double>(i) / (kSin - 1);
      const double cos_beta = std::sqrt(std::max(0.0, 1.0 - sin_beta * sin_beta));
      for (int j = 0; j < kCos; ++j) {
        const double cos_elongation = -1.0 + 2.0 * j / (kCos - 1);
        const double c = cos_beta > 0.0 ? std::clamp(cos_elongation / cos_beta, -1.0, 1.0) : 0.0;
        value[static_cast<std::size_t>(i) * kCos + j] =
            static_cast<float>(grid.At(std::acos(c) * (180.0 / kPi), std::asin(sin_beta) * (180.0 / kPi)));
      }
    }
  }
  float At(double abs_sin_beta, double cos_elongation) const {
    const double x = std::min(abs_sin_beta, 1.0) * (kSin - 1);
    const double y = (std::clamp(cos_elongation, -1.0, 1.0) + 1.0) * (0.5 * (kCos - 1));
    const int i = std::min(static_cast<int>(x), kSin - 2);
    const int j = std::min(static_cast<int>(y), kCos - 2);
    const float fx = static_cast<float>(x - i);
    const float fy = static_cast<float>(y - j);
    const float* row = &value[static_cast<std::size_t>(i) * kCos + j];
    return (1.0f - fx) * ((1.0f - fy) * row[0] + fy * row[1]) + fx * ((1.0f - fy) * row[kCos] + fy * row[kCos + 1]);
  }
};

const ZodiacalDotGrid& ZodiacalDots() {
  static const ZodiacalDotGrid grid;
  return grid;
}

// J2000 equatorial to galactic coordinates (galactic = M equatorial): the north galactic pole at
// right ascension 192.85948, declination +27.12825 degrees and the galactic centre (l = b = 0) at
// 266.40510, -28.93617 (the Hipparcos catalogue's definition, ESA 1997, vol. 1, section 1.5.3).
glm::dmat3 EquatorialToGalactic() {
  const auto direction = [](double ra_deg, double dec_deg) {
    const double ra = ra_deg * kPi / 180.0, dec = dec_deg * kPi / 180.0;
    return glm::dvec3(std::cos(dec) * std::cos(ra), std::cos(dec) * std::sin(ra), std::sin(dec));
  };
  const glm::dvec3 z = direction(192.85948, 27.12825);
  glm::dvec3 x = direction(266.40510, -28.93617);
  x = glm::normalize(x - glm::dot(x, z) * z);
  const glm::dvec3 y = glm::cross(z, x);
  return glm::transpose(glm::dmat3(x, y, z));  // rows x, y, z
}

// Table 35 with its unmapped cells (-1) filled by linear interpolation along their latitude
// between the nearest mapped cells on either side.
struct StarlightNodes {
  std::array<std::array<double, data::kStarlightLongitudes>, data::kStarlightLatitudes> s10{};
  StarlightNodes() {
    constexpr int n = data::kStarlightLongitudes;
    for (int k = 0; k < data::kStarlightLatitudes; ++k) {
      for (int i = 0; i < n; ++i) {
        const double value = data::kStarlightS10Sun[k][i];
        if (value >= 0.0) {
          s10[k][i] = value;
          continue;
        }
        int left = 1, right = 1;
        while (data::kStarlightS10Sun[k][(i - left + n) % n] < 0.0) ++left;
        while (data::kStarlightS10Sun[k][(i + right) % n] < 0.0) ++right;
        const double a = data::kStarlightS10Sun[k][(i - left + n) % n];
        const double b = data::kStarlightS10Sun[k][(i + right) % n];
        s10[k][i] = a + (b - a) * left / static_cast<double>(left + right);
      }
    }
  }
};

const StarlightNodes& Starlight() {
  static const StarlightNodes nodes;
  return nodes;
}

// Bilinear in galactic longitude (periodic, 10 degree steps) and latitude (the table's nodes; held
// beyond +-80 degrees) of a node table.
template <typename Nodes>
double GalacticBilinear(const Nodes& nodes, double longitude_deg, double latitude_deg) {
  constexpr int n = data::kStarlightLongitudes;
  const double l = longitude_deg - 360.0 * std::floor(longitude_deg / 360.0);
  const int i = std::min(static_cast<int>(l / 10.0), n - 1);
  const double fl = l / 10.0 - i;
  const double* lat = data::kStarlightLatitudeDeg;
  const double b = std::clamp(latitude_deg, lat[0], lat[data::kStarlightLatitudes - 1]);
  int k = 0;
  while (k < data::kStarlightLatitudes - 2 && b > lat[k + 1]) ++k;
  const double fb = (b - lat[k]) / (lat[k + 1] - lat[k]);
  const auto at = [&](int kk, int ii) { return nodes[kk][ii % n]; };
  return (1 - fb) * ((1 - fl) * at(k, i) + fl * at(k, i + 1)) + fb * ((1 - fl) * at(k + 1, i) + fl * at(k + 1, i + 1));
}

// The local starlight grid (NightSky::starlight_grid) along `view`, bilinearly: the lookup of
// StarlightValue and of the renderers' per-pixel pass.
float StarlightGridValue(const float* grid, const glm::dvec3& view) {
  constexpr int kSide = NightSky::kStarlightSide;
  const double n = std::abs(view.x) + std::abs(view.y) + std::abs(view.z);
  if (!(n > 0.0)) return 0.0f;
  const double u = view.x / n, w = view.y / n;
  const double x = std::clamp(u + w + 1.0, 0.0, 2.0) * (0.5 * (kSide - 1));
  const double y = std::clamp(u - w + 1.0, 0.0, 2.0) * (0.5 * (kSide - 1));
  const int i = std::min(static_cast<int>(x), kSide - 2);
  const int j = std::min(static_cast<int>(y), kSide - 2);
  const float fx = static_cast<float>(x - i);
  const float fy = static_cast<float>(y - j);
  const float* row = grid + (view.z < 0.0 ? kSide * kSide : 0) + static_cast<std::size_t>(j) * kSide + i;
  return (1.0f - fy) * ((1.0f - fx) * row[0] + fx * row[1]) + fy * ((1.0f - fx) * row[kSide] + fx * row[kSide + 1]);
}

bool IsUnit(const glm::dvec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) && std::abs(glm::length(v) - 1.0) < 1e-6;
}

}  // namespace

void ClipToGamut(float* rgb) {
  const float lowest = std::min({rgb[0], rgb[1], rgb[2]});
  if (lowest >= 0.0f) return;
  const float y = 0.2126f * rgb[0] + 0.7152f * rgb[1] + 0.0722f * rgb[2];
  if (y <= 0.0f) {
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    return;
  }
  const float t = -lowest / (y - lowest);
  for (int k = 0; k < 3; ++k) rgb[k] = std::max(0.0f, (1.0f - t) * rgb[k] + t * y);
}

glm::dvec3 DefaultEclipticPole(const glm::dvec3& sun_direction) {
  const glm::dvec3 up(0.0, 0.0, 1.0);
  glm::dvec3 pole = up - glm::dot(up, sun_direction) * sun_direction;
  // The sun at the zenith or nadir: any pole at right angles to it; the north one.
  if (glm::length(pole) < 1e-9) pole = glm::dvec3(0.0, 1.0, 0.0);
  return glm::normalize(pole);
}

NightSky::NightSky(const AtmosphereParameters& parameters, double altitude_m, const glm::dvec3& sun_direction,
                   const glm::dvec3& ecliptic_pole)
    : channel_count_(parameters.channel_count()) {
  if (!std::isfinite(altitude_m) || altitude_m < 0.0) {
    throw Error("the night sky needs a finite altitude >= 0 m (got " + std::to_string(altitude_m) + ")");
  }
  if (!IsUnit(sun_direction)) throw Error("the night sky needs a unit sun direction");
  const NightSkySettings& settings = parameters.night_sky;
  // The tables serve the stars too (SetStars), which --no-night-glow (enabled false) keeps.
  active_ = parameters.geometry == Geometry::kSpherical && channel_count_ > 0;
  glow_ = settings.enabled;
  if (!active_) return;
  sun_direction_ = sun_direction;
  if (glm::length(ecliptic_pole) == 0.0) {
    ecliptic_pole_ = DefaultEclipticPole(sun_direction);
  } else {
    if (!IsUnit(ecliptic_pole)) throw Error("the ecliptic pole must be a unit vector");
    // At right angles to the sun by construction of the ecliptic; remove rounding.
    ecliptic_pole_ = glm::normalize(ecliptic_pole - glm::dot(ecliptic_pole, sun_direction) * sun_direction);
  }

  wavelengths_nm_ = parameters.wavelengths_nm;
  airglow_zenith_ = ProjectAirglow(parameters.wavelengths_nm);
  for (double& g : airglow_zenith_) g *= glow_ ? settings.airglow_scale : 0.0;
  // Table 17's unit (1e-8 W m^-2 sr^-1 um^-1 = 1e-11 W m^-2 sr^-1 nm^-1) over the solar spectral
  // irradiance at 500 nm: a solar-spectrum radiance per unit solar irradiance.
  zodiacal_relative_ = glow_ ? settings.zodiacal_scale * 1e-11 / SolarSpectralIrradiance(500.0) : 0.0;
  // 1 S10(sun) is 6.61e-12 of the solar irradiance per steradian (Leinert et al. 1998, section 2):
  // a solar-coloured radiance, the same relative value in every channel.
  starlight_relative_ = glow_ ? settings.starlight_scale * 6.61e-12 : 0.0;
  frame_ = CelestialFrame::FromSun(sun_direction);

  const std::size_t n = channel_count_;
  const std::size_t batches = ChannelBatchCount(n);
  std::vector<shared::AtmosphereParameters> shared_batches;
  for (std::size_t b = 0; b < batches; ++b) shared_batches.push_back(ToSharedParameters(parameters, b));
  const double bottom = parameters.ground_radius_m;
  const double top = parameters.top_radius_m;
  const double r = bottom + altitude_m;
  const double shell_low = bottom + settings.airglow_altitude_m - 0.5 * settings.airglow_thickness_m;
  const double shell_high = shell_low + settings.airglow_thickness_m;
  airglow_path_.assign(static_cast<std::size_t>(kAngles) * n, 0.0);
  transmittance_.assign(static_cast<std::size_t>(kAngles) * n, 0.0);
  oneapi::tbb::parallel_for(0, kAngles, [&](int a) {
    const double mu = std::clamp(-1.0 + 2.0 * a / (kAngles - 1), -1.0, 1.0);
    const bool hits_ground = r * r * (mu * mu - 1.0) + bottom * bottom >= 0.0 && mu < 0.0;
    const double t_end = hits_ground ? -r * mu - std::sqrt(std::max(r * r * (mu * mu - 1.0) + bottom * bottom, 0.0))
                                     : std::numeric_limits<double>::infinity();
    // Where the ray first goes below the shell: from there on, the air lies between the emission
    // and the observer.
    double t_below = std::numeric_limits<double>::infinity();
    if (r < shell_low) {
      t_below = 0.0;
    } else {
      const double d = r * r * (mu * mu - 1.0) + shell_low * shell_low;
      if (d > 0.0 && -r * mu - std::sqrt(d) > 0.0) t_below = -r * mu - std::sqrt(d);
    }
    const auto high = LengthInsideSphere(r, mu, shell_high, t_end, t_below);
    const auto low = LengthInsideSphere(r, mu, shell_low, t_end, t_below);
    const double near = (high[0] - low[0]) / settings.airglow_thickness_m;
    const double far = (high[1] - low[1]) / settings.airglow_thickness_m;
    // Transmittance along the whole ray through the atmosphere (0 where it meets the ground).
    for (std::size_t b = 0; b < batches; ++b) {
      shared::vec3 value(0.0);
      if (!hits_ground) {
        double r_start = r;
        double mu_start = mu;
        bool crosses = true;
        if (r > top) {
          const double d = r * r * (mu * mu - 1.0) + top * top;
          crosses = d > 0.0 && mu < 0.0;
          if (crosses) {
            const double entry = -r * mu - std::sqrt(d);
            r_start = top;
            mu_start = std::clamp((r * mu + entry) / top, -1.0, 1.0);
          }
        }
        value = crosses ? shared::ComputeTransmittanceToTopAtmosphereBoundary(shared_batches[b], r_start, mu_start,
                                                                              kTransmittanceIntervals)
                        : shared::vec3(1.0);
      }
      for (std::size_t k = 0; k < 3 && 3 * b + k < n; ++k) {
        const std::size_t c = 3 * b + k;
        const double tc = value[static_cast<int>(k)];
        transmittance_[static_cast<std::size_t>(a) * n + c] = tc;
        airglow_path_[static_cast<std::size_t>(a) * n + c] = airglow_zenith_[c] * (near + far * tc);
      }
    }
  });
  BuildStarlight();
}

void NightSky::SetFrame(const CelestialFrame& frame) {
  frame_ = frame;
  if (!active_) return;
  ecliptic_pole_ = glm::normalize(frame.EclipticPole() - glm::dot(frame.EclipticPole(), sun_direction_) * sun_direction_);
  BuildStarlight();
}

void NightSky::SetStars(const StarCatalogue& catalogue, const CelestialFrame& frame) {
  frame_ = frame;
  if (!active_) return;
  stars_ = &catalogue;
  const std::size_t n = channel_count_;
  star_irradiance_.assign(catalogue.stars().size() * n, 0.0);
  for (std::size_t i = 0; i < catalogue.stars().size(); ++i) {
    StarRelativeIrradiance(catalogue.stars()[i], wavelengths_nm_, std::span<double>(&star_irradiance_[i * n], n));
  }
  SetFrame(frame);
}

double NightSky::StarlightS10(double longitude_deg, double latitude_deg) {
  return GalacticBilinear(Starlight().s10, longitude_deg, latitude_deg);
}

// Table 35 less the catalogue's stars that it holds and SetStars draws (fainter than V 6.5, the
// Pioneer catalogue's limit): each such star's S10 (10^(-0.4 (V - 10)) per square degree) over the
// cell of its nearest node (10 degrees of longitude, latitude half-way to the next nodes), at least
// 0; then resampled on the local frame through frame_.
void NightSky::BuildStarlight() {
  starlight_grid_.clear();
  if (!active_ || !(starlight_relative_ > 0.0)) return;
  constexpr int kLat = data::kStarlightLatitudes;
  constexpr int kLon = data::kStarlightLongitudes;
  static const glm::dmat3 to_galactic = EquatorialToGalactic();
  std::array<std::array<double, kLon>, kLat> nodes = Starlight().s10;
  if (stars_ != nullptr) {
    const double* lat = data::kStarlightLatitudeDeg;
    std::array<std::array<double, kLon>, kLat> drawn{};
    for (const Star& star : stars_->stars()) {
      if (!(star.v_mag > 6.5)) continue;
      const glm::dvec3 g = to_galactic * star.direction;
      double l = std::atan2(g.y, g.x) * 180.0 / kPi;
      if (l < 0.0) l += 360.0;
      const double b = std::asin(std::clamp(g.z, -1.0, 1.0)) * 180.0 / kPi;
      const int i = static_cast<int>(std::lround(l / 10.0)) % kLon;
      int k = 0;
      for (int kk = 1; kk < kLat; ++kk) {
        if (std::abs(lat[kk] - b) < std::abs(lat[k] - b)) k = kk;
      }
      drawn[k][i] += std::pow(10.0, -0.4 * (star.v_mag - 10.0));
    }
    for (int k = 0; k < kLat; ++k) {
      const double low = k == 0 ? -90.0 : 0.5 * (lat[k - 1] + lat[k]);
      const double high = k == kLat - 1 ? 90.0 : 0.5 * (lat[k] + lat[k + 1]);
      const double square_degrees =
          (10.0 * kPi / 180.0) * (std::sin(high * kPi / 180.0) - std::sin(low * kPi / 180.0)) * (180.0 / kPi) * (180.0 / kPi);
      for (int i = 0; i < kLon; ++i) nodes[k][i] = std::max(0.0, nodes[k][i] - drawn[k][i] / square_degrees);
    }
  }
  const glm::dmat3 local_to_galactic = to_galactic * glm::transpose(frame_.equatorial_to_local());
  constexpr int kSide = kStarlightSide;
  starlight_grid_.assign(2 * static_cast<std::size_t>(kSide) * kSide, 0.0f);
  for (int hemisphere = 0; hemisphere < 2; ++hemisphere) {
    for (int j = 0; j < kSide; ++j) {
      for (int i = 0; i < kSide; ++i) {
        // The cell's direction: s = u + w, t = u - w, |u| + |w| + |z| = 1.
        const double s_coord = -1.0 + 2.0 * i / (kSide - 1);
        const double t_coord = -1.0 + 2.0 * j / (kSide - 1);
        const double u = 0.5 * (s_coord + t_coord), w = 0.5 * (s_coord - t_coord);
        const double z = std::max(0.0, 1.0 - std::abs(u) - std::abs(w)) * (hemisphere == 0 ? 1.0 : -1.0);
        const glm::dvec3 g = local_to_galactic * glm::normalize(glm::dvec3(u, w, z));
        const double l = std::atan2(g.y, g.x) * 180.0 / kPi;
        const double b = std::asin(std::clamp(g.z, -1.0, 1.0)) * 180.0 / kPi;
        starlight_grid_[(static_cast<std::size_t>(hemisphere) * kSide + j) * kSide + i] =
            static_cast<float>(starlight_relative_ * GalacticBilinear(nodes, l, b));
      }
    }
  }
}

double NightSky::StarlightValue(const glm::dvec3& view) const {
  if (starlight_grid_.empty()) return 0.0;
  return StarlightGridValue(starlight_grid_.data(), view);
}

void NightSky::StarlightRadiance(const glm::dvec3& view, std::span<double> out) const {
  std::fill(out.begin(), out.end(), 0.0);
  const double value = StarlightValue(view);
  if (!(value > 0.0)) return;
  Transmittance(view.z, out);
  for (double& o : out) o *= value;
}

void NightSky::Transmittance(double mu, std::span<double> out) const {
  std::fill(out.begin(), out.end(), 0.0);
  if (!active_) return;
  int a;
  double f;
  Locate(mu, a, f);
  for (std::size_t c = 0; c < channel_count_ && c < out.size(); ++c) {
    out[c] = (1 - f) * transmittance_[a * channel_count_ + c] + f * transmittance_[(a + 1) * channel_count_ + c];
  }
}

void NightSky::Locate(double mu, int& index, double& fraction) const {
  const double x = (std::clamp(mu, -1.0, 1.0) + 1.0) * (0.5 * (kAngles - 1));
  index = std::min(static_cast<int>(x), kAngles - 2);
  fraction = x - index;
}

// Table 17's value along `view` (its unit), from the ecliptic coordinates relative to the sun.
// The same lookup as the renderers' pass (Folded::Add), so that Radiance and images agree.
double NightSky::ZodiacalTableValue(const glm::dvec3& view) const {
  return ZodiacalDots().At(std::abs(glm::dot(view, ecliptic_pole_)), glm::dot(view, sun_direction_));
}

double NightSky::ZodiacalBrightness500(const glm::dvec3& view) const {
  if (!active_) return 0.0;
  return ZodiacalTableValue(view) * zodiacal_relative_ * SolarSpectralIrradiance(500.0);
}

void NightSky::AirglowRadiance(const glm::dvec3& view, std::span<double> out) const {
  std::fill(out.begin(), out.end(), 0.0);
  if (!active_) return;
  int a;
  double f;
  Locate(view.z, a, f);
  for (std::size_t c = 0; c < channel_count_; ++c) {
    out[c] = (1 - f) * airglow_path_[a * channel_count_ + c] + f * airglow_path_[(a + 1) * channel_count_ + c];
  }
}

void NightSky::ZodiacalRadiance(const glm::dvec3& view, std::span<double> out) const {
  std::fill(out.begin(), out.end(), 0.0);
  if (!active_) return;
  int a;
  double f;
  Locate(view.z, a, f);
  const double z = ZodiacalTableValue(view) * zodiacal_relative_;
  for (std::size_t c = 0; c < channel_count_; ++c) {
    out[c] = z * ((1 - f) * transmittance_[a * channel_count_ + c] + f * transmittance_[(a + 1) * channel_count_ + c]);
  }
}

void NightSky::Radiance(const glm::dvec3& view, std::span<double> out) const {
  std::vector<double> zodiacal(channel_count_), starlight(channel_count_);
  AirglowRadiance(view, out);
  ZodiacalRadiance(view, zodiacal);
  StarlightRadiance(view, starlight);
  for (std::size_t c = 0; c < channel_count_; ++c) out[c] += zodiacal[c] + starlight[c];
}

std::span<const float> NightSky::ZodiacalGrid() { return ZodiacalDots().value; }

void NightSky::Folded::Stars(std::vector<glm::dvec3>& directions, std::vector<float>& values) const {
  directions.clear();
  values.clear();
  if (night_ == nullptr || night_->stars_ == nullptr) return;
  const std::size_t n = night_->channel_count_;
  const std::size_t m = static_cast<std::size_t>(outputs_);
  const std::vector<Star>& stars = night_->stars_->stars();
  std::vector<double> transmittance(n);
  std::vector<float> star(m);
  for (std::size_t i = 0; i < stars.size(); ++i) {
    const glm::dvec3 d = night_->frame_.ToLocal(stars[i]);
    night_->Transmittance(d.z, transmittance);
    std::fill(star.begin(), star.end(), 0.0f);
    bool any = false;
    for (std::size_t c = 0; c < n; ++c) {
      const double value = night_->star_irradiance_[i * n + c] * transmittance[c];
      if (value == 0.0) continue;
      any = true;
      for (std::size_t k = 0; k < m; ++k) star[k] += static_cast<float>(weights_[c * m + k] * value);
    }
    if (!any) continue;  // hidden by the ground (transmittance 0)
    if (m == 3) ClipToGamut(star.data());  // a red star low in the sky may leave linear sRGB
    directions.push_back(d);
    values.insert(values.end(), star.begin(), star.end());
  }
}

NightSky::Folded NightSky::Fold(std::span<const glm::vec3> weights, int outputs) const {
  if (weights.size() != channel_count_) throw Error("NightSky::Fold needs one weight per channel");
  if (outputs < 1 || outputs > 3) throw Error("NightSky::Fold folds into 1 to 3 outputs");
  Folded folded;
  folded.night_ = this;
  folded.outputs_ = outputs;
  for (std::size_t c = 0; c < weights.size(); ++c) {
    for (int k = 0; k < outputs; ++k) folded.weights_.push_back(weights[c][k]);
  }
  if (!active_) return folded;
  const std::size_t n = channel_count_;
  folded.airglow_.assign(static_cast<std::size_t>(kAngles) * outputs, 0.0f);
  folded.transmitted_.assign(static_cast<std::size_t>(kAngles) * outputs, 0.0f);
  for (int a = 0; a < kAngles; ++a) {
    for (int k = 0; k < outputs; ++k) {
      double airglow = 0.0;
      double transmitted = 0.0;
      for (std::size_t c = 0; c < n; ++c) {
        airglow += weights[c][k] * airglow_path_[a * n + c];
        transmitted += weights[c][k] * transmittance_[a * n + c];
      }
      folded.airglow_[static_cast<std::size_t>(a) * outputs + k] = static_cast<float>(airglow);
      folded.transmitted_[static_cast<std::size_t>(a) * outputs + k] = static_cast<float>(transmitted);
    }
    if (outputs == 3) {
      ClipToGamut(&folded.airglow_[static_cast<std::size_t>(a) * 3]);
      ClipToGamut(&folded.transmitted_[static_cast<std::size_t>(a) * 3]);
    }
  }
  return folded;
}

NightSky::Folded NightSky::Scaled(std::span<const double> scale) const {
  if (scale.size() != channel_count_) throw Error("NightSky::Scaled needs one value per channel");
  Folded folded;
  folded.night_ = this;
  const std::size_t n = channel_count_;
  folded.outputs_ = static_cast<int>(n);
  folded.weights_.assign(n * n, 0.0f);
  for (std::size_t c = 0; c < n; ++c) folded.weights_[c * n + c] = static_cast<float>(scale[c]);
  if (!active_) return folded;
  folded.airglow_.assign(static_cast<std::size_t>(kAngles) * n, 0.0f);
  folded.transmitted_.assign(static_cast<std::size_t>(kAngles) * n, 0.0f);
  for (std::size_t i = 0; i < static_cast<std::size_t>(kAngles) * n; ++i) {
    folded.airglow_[i] = static_cast<float>(scale[i % n] * airglow_path_[i]);
    folded.transmitted_[i] = static_cast<float>(scale[i % n] * transmittance_[i]);
  }
  return folded;
}

namespace {

// The per-pixel loop of Folded::Add, with the output count a template parameter when it is 3 (the
// colour of every luminance render: the inner loop then unrolls) and a run-time one otherwise.
template <int kFixed>
void AddNightSkyPixels(std::span<const glm::dvec3> views, std::span<float> out, std::size_t outputs,
                       const float* airglow, const float* transmitted, const glm::dvec3& pole,
                       const glm::dvec3& sun, const ZodiacalDotGrid* dots, float zodiacal_scale,
                       const float* starlight) {
  const std::size_t m = kFixed > 0 ? static_cast<std::size_t>(kFixed) : outputs;
  constexpr double kScale = 0.5 * (kAngles - 1);
  float* o = out.data();
  for (std::size_t i = 0; i < views.size(); ++i, o += m) {
    const glm::dvec3 v = views[i];
    if (v.x == 0.0 && v.y == 0.0 && v.z == 0.0) continue;
    const double x = (std::clamp(v.z, -1.0, 1.0) + 1.0) * kScale;
    const int a = std::min(static_cast<int>(x), kAngles - 2);
    const float f = static_cast<float>(x - a);
    float z = dots != nullptr ? zodiacal_scale * dots->At(std::abs(pole.x * v.x + pole.y * v.y + pole.z * v.z),
                                                          sun.x * v.x + sun.y * v.y + sun.z * v.z)
                              : 0.0f;
    if (starlight != nullptr) z += StarlightGridValue(starlight, v);
    const float* a0 = airglow + a * m;
    const float* t0 = transmitted + a * m;
    for (std::size_t k = 0; k < m; ++k) {
      o[k] += (1.0f - f) * (a0[k] + z * t0[k]) + f * (a0[m + k] + z * t0[m + k]);
    }
  }
}

}  // namespace

void NightSky::Folded::Add(std::span<const glm::dvec3> views, std::span<float> out) const {
  if (night_ == nullptr || !night_->active_ || !night_->glow_) return;
  const ZodiacalDotGrid* dots = night_->zodiacal_relative_ > 0.0 ? &ZodiacalDots() : nullptr;
  const std::size_t m = static_cast<std::size_t>(outputs_);
  const float zodiacal_scale = static_cast<float>(night_->zodiacal_relative_);
  const float* starlight = night_->starlight_grid_.empty() ? nullptr : night_->starlight_grid_.data();
  if (m == 3) {
    AddNightSkyPixels<3>(views, out, m, airglow_.data(), transmitted_.data(), night_->ecliptic_pole_,
                         night_->sun_direction_, dots, zodiacal_scale, starlight);
  } else {
    AddNightSkyPixels<0>(views, out, m, airglow_.data(), transmitted_.data(), night_->ecliptic_pole_,
                         night_->sun_direction_, dots, zodiacal_scale, starlight);
  }
}

}  // namespace atmo
