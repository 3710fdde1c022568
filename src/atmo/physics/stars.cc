// The stars: Stellarium 0.22's zone catalogue, the celestial frame and the stars' light
// (include/atmo/stars.h).
#include "atmo/stars.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <mutex>
#include <numbers>
#include <optional>
#include <string>

#include "atmo/error.h"
#include "atmo/night_sky.h"
#include "atmo/spectrum.h"
#include "atmo/sun_position.h"

namespace atmo {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDegToRad = kPi / 180.0;
constexpr std::uint32_t kMagic = 0x835f040a;  // the files' first 4 bytes, little-endian
constexpr std::size_t kHeaderBytes = 32;
constexpr std::size_t kStar1Bytes = 28;
constexpr double kStar1MaxPosition = 2147483647.0;  // the largest x0, x1 of a Star1 record

// The icosahedron of Stellarium's geodesic grid: its 12 corners and 20 faces, in the order the
// catalogue's zones are numbered.
std::array<glm::dvec3, 12> IcosahedronCorners() {
  const double g = 0.5 * (1.0 + std::sqrt(5.0));
  const double b = 1.0 / std::sqrt(1.0 + g * g);
  const double a = b * g;
  return {glm::dvec3(a, -b, 0), glm::dvec3(a, b, 0),   glm::dvec3(-a, b, 0),  glm::dvec3(-a, -b, 0),
          glm::dvec3(0, a, -b), glm::dvec3(0, a, b),   glm::dvec3(0, -a, b),  glm::dvec3(0, -a, -b),
          glm::dvec3(-b, 0, a), glm::dvec3(b, 0, a),   glm::dvec3(b, 0, -a),  glm::dvec3(-b, 0, -a)};
}

constexpr int kIcosahedronFaces[20][3] = {{1, 0, 10}, {0, 1, 9},  {0, 9, 6},   {9, 8, 6},  {0, 7, 10},
                                          {6, 7, 0},  {7, 6, 3},  {6, 8, 3},   {11, 10, 7}, {7, 3, 11},
                                          {3, 2, 11}, {2, 3, 8},  {10, 11, 4}, {2, 4, 11}, {5, 4, 2},
                                          {2, 8, 5},  {4, 1, 10}, {4, 5, 1},   {5, 9, 1},  {8, 9, 5}};

using Triangle = std::array<glm::dvec3, 3>;

// The zones of a level: each face subdivided `level` times, children in the order (c0, e2, e1),
// (e2, c1, e0), (e1, e0, c2), (e0, e1, e2) with e_i the normalised midpoint opposite corner i.
void Subdivide(const Triangle& t, int level, std::vector<Triangle>& out) {
  if (level == 0) {
    out.push_back(t);
    return;
  }
  const glm::dvec3 e0 = glm::normalize(t[1] + t[2]);
  const glm::dvec3 e1 = glm::normalize(t[2] + t[0]);
  const glm::dvec3 e2 = glm::normalize(t[0] + t[1]);
  Subdivide({t[0], e2, e1}, level - 1, out);
  Subdivide({e2, t[1], e0}, level - 1, out);
  Subdivide({e1, e0, t[2]}, level - 1, out);
  Subdivide({e0, e1, e2}, level - 1, out);
}

struct Zone {
  glm::dvec3 centre;
  glm::dvec3 axis0;
  glm::dvec3 axis1;
};

std::vector<Zone> Zones(int level, double& position_scale) {
  const std::array<glm::dvec3, 12> corners = IcosahedronCorners();
  std::vector<Triangle> triangles;
  for (const auto& face : kIcosahedronFaces) {
    Subdivide({corners[face[0]], corners[face[1]], corners[face[2]]}, level, triangles);
  }
  std::vector<Zone> zones;
  double scale = 0.0;
  for (const Triangle& t : triangles) {
    Zone z;
    z.centre = glm::normalize(t[0] + t[1] + t[2]);
    z.axis0 = glm::normalize(glm::cross(glm::dvec3(0, 0, 1), z.centre));
    z.axis1 = glm::cross(z.centre, z.axis0);
    // The tangent-plane extent of the zone's corners sets the unit of the stored positions.
    for (const glm::dvec3& c : t) {
      const double mu0 = glm::dot(c - z.centre, z.axis0);
      const double mu1 = glm::dot(c - z.centre, z.axis1);
      const double f = 1.0 / std::sqrt(1.0 - mu0 * mu0 - mu1 * mu1);
      scale = std::max({scale, std::abs(mu0) * f, std::abs(mu1) * f});
    }
    zones.push_back(z);
  }
  position_scale = scale / kStar1MaxPosition;
  return zones;
}

std::uint32_t U32(const unsigned char* p) {
  return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 |
         static_cast<std::uint32_t>(p[2]) << 16 | static_cast<std::uint32_t>(p[3]) << 24;
}
std::int32_t I32(const unsigned char* p) { return static_cast<std::int32_t>(U32(p)); }

// Reads one Star1 file (record type 0) into `out`, the stars at most `limit` faint.
void ReadStarFile(const std::filesystem::path& path, double limit, std::vector<Star>& out) {
  const std::string name = "star catalogue '" + path.string() + "'";
  std::ifstream file(path, std::ios::binary);
  if (!file) throw Error("cannot read " + name);
  const std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  if (bytes.size() < kHeaderBytes) throw Error(name + " is truncated (no header)");
  const unsigned char* h = bytes.data();
  if (U32(h) != kMagic) throw Error(name + " is not a Stellarium star catalogue (wrong magic number)");
  const std::uint32_t type = U32(h + 4);
  const std::uint32_t level = U32(h + 16);
  const double mag_min = I32(h + 20);
  const double mag_range = U32(h + 24);
  const double mag_steps = U32(h + 28);
  if (type != 0) throw Error(name + " has record type " + std::to_string(type) + "; atmo reads type 0 (Star1) only");
  if (level > 4 || mag_steps <= 0.0 || mag_range <= 0.0) throw Error(name + " has an invalid header");
  double position_scale = 0.0;
  const std::vector<Zone> zones = Zones(static_cast<int>(level), position_scale);
  std::size_t offset = kHeaderBytes;
  if (bytes.size() < offset + 4 * zones.size()) throw Error(name + " is truncated (zone counts)");
  std::vector<std::uint32_t> counts(zones.size());
  std::size_t total = 0;
  for (std::size_t z = 0; z < zones.size(); ++z) {
    counts[z] = U32(h + offset + 4 * z);
    total += counts[z];
  }
  offset += 4 * zones.size();
  if (bytes.size() != offset + total * kStar1Bytes) {
    throw Error(name + " is truncated or corrupt (" + std::to_string(bytes.size()) + " bytes for " +
                std::to_string(total) + " stars)");
  }
  // 0.1 mas per year in radians.
  const double motion_unit = 1e-4 / 3600.0 * kDegToRad;
  for (std::size_t z = 0; z < zones.size(); ++z) {
    const Zone& zone = zones[z];
    for (std::uint32_t k = 0; k < counts[z]; ++k, offset += kStar1Bytes) {
      const unsigned char* r = h + offset;
      const double v = (mag_min + r[13] * mag_range / mag_steps) / 1000.0;
      if (v > limit) continue;
      Star star;
      star.hip = static_cast<int>(r[0] | r[1] << 8 | r[2] << 16);
      const double x0 = I32(r + 4) * position_scale;
      const double x1 = I32(r + 8) * position_scale;
      const glm::dvec3 unnormalised = zone.centre + x0 * zone.axis0 + x1 * zone.axis1;
      star.direction = glm::normalize(unnormalised);
      // The motion of the unnormalised point, projected onto the tangent plane of the direction.
      const glm::dvec3 velocity = (I32(r + 16) * motion_unit) * zone.axis0 + (I32(r + 20) * motion_unit) * zone.axis1;
      const double length = glm::length(unnormalised);
      star.motion_per_yr = (velocity - glm::dot(velocity, star.direction) * star.direction) / length;
      star.v_mag = static_cast<float>(v);
      star.b_v = static_cast<float>(r[12] * 4.0 / 127.0 - 0.5);
      out.push_back(star);
    }
  }
}

// The mean obliquity of the ecliptic (Meeus eq. 22.2), radians.
double MeanObliquity(double julian_day) {
  const double t = (julian_day - 2451545.0) / 36525.0;
  return (23.4392911 - (46.8150 * t + 0.00059 * t * t - 0.001813 * t * t * t) / 3600.0) * kDegToRad;
}

}  // namespace

std::filesystem::path StarCatalogue::DefaultFolder() {
  if (const char* folder = std::getenv("ATMO_STAR_CATALOGUE"); folder != nullptr && *folder != '\0') return folder;
  return "/usr/share/stellarium/stars/default";
}

StarCatalogue StarCatalogue::Load(const std::filesystem::path& folder, double limiting_magnitude) {
  if (!std::isfinite(limiting_magnitude)) throw Error("the stars' limiting magnitude must be finite");
  std::error_code error;
  if (!std::filesystem::is_directory(folder, error)) {
    throw Error("no star catalogue folder '" + folder.string() + "' (install Debian's stellarium-data)");
  }
  StarCatalogue catalogue;
  catalogue.limiting_magnitude_ = limiting_magnitude;
  // stellarium-data's first files: V <= 6 and 6 < V <= 7.5.
  ReadStarFile(folder / "stars_0_0v0_8.cat", limiting_magnitude, catalogue.stars_);
  if (limiting_magnitude > 6.0) ReadStarFile(folder / "stars_1_0v0_8.cat", limiting_magnitude, catalogue.stars_);
  return catalogue;
}

const StarCatalogue& StarCatalogue::Default() {
  static std::mutex mutex;
  static std::optional<StarCatalogue> catalogue;
  const std::lock_guard<std::mutex> lock(mutex);
  if (!catalogue) catalogue = Load(DefaultFolder());
  return *catalogue;
}

CelestialFrame CelestialFrame::FromDate(double julian_day_utc, double latitude_deg, double longitude_deg) {
  if (!std::isfinite(julian_day_utc)) throw Error("the sky's frame needs a finite date");
  if (!(latitude_deg >= -90.0 && latitude_deg <= 90.0) || !(longitude_deg >= -180.0 && longitude_deg < 360.0)) {
    throw Error("the sky's frame needs a latitude in [-90, 90] and a longitude in [-180, 360) degrees");
  }
  const double t = (julian_day_utc - 2451545.0) / 36525.0;
  // Precession J2000 -> date (Meeus eq. 21.3): zeta, z, theta in arcseconds.
  const double arcsec = kDegToRad / 3600.0;
  const double zeta = (2306.2181 * t + 0.30188 * t * t + 0.017998 * t * t * t) * arcsec;
  const double z = (2306.2181 * t + 1.09468 * t * t + 0.018203 * t * t * t) * arcsec;
  const double theta = (2004.3109 * t - 0.42665 * t * t - 0.041833 * t * t * t) * arcsec;
  // r_date = Rz(z) Ry(-theta) Rz(zeta) r_J2000 with active rotations.
  const auto active_z = [](double a) {
    const double c = std::cos(a), s = std::sin(a);
    return glm::dmat3(c, s, 0, -s, c, 0, 0, 0, 1);
  };
  const auto active_y = [](double a) {
    const double c = std::cos(a), s = std::sin(a);
    return glm::dmat3(c, 0, -s, 0, 1, 0, s, 0, c);
  };
  const glm::dmat3 precession = active_z(z) * active_y(-theta) * active_z(zeta);
  // Local sidereal time: Greenwich mean (Meeus eq. 12.4) plus the longitude.
  const double lst = (GreenwichMeanSiderealTimeDeg(julian_day_utc) + longitude_deg) * kDegToRad;
  const double phi = latitude_deg * kDegToRad;
  const double cl = std::cos(lst), sl = std::sin(lst), cp = std::cos(phi), sp = std::sin(phi);
  // Equatorial of date -> (east, north, up): H = LST - RA (include/atmo/stars.h).
  const glm::dmat3 horizontal(-sl, -sp * cl, cp * cl,   // column x
                              cl, -sp * sl, cp * sl,    // column y
                              0.0, cp, sp);             // column z
  CelestialFrame frame;
  frame.to_local_ = horizontal * precession;
  frame.julian_day_utc_ = julian_day_utc;
  return frame;
}

CelestialFrame CelestialFrame::FromSun(const glm::dvec3& sun_direction) {
  const double epsilon = MeanObliquity(2451545.0);
  // Ecliptic (J2000) of the sun at longitude 270 degrees and of the pole, and their local places.
  const glm::dvec3 sun_ecliptic(0.0, -1.0, 0.0);
  const glm::dvec3 pole_ecliptic(0.0, 0.0, 1.0);
  const glm::dvec3 third_ecliptic = glm::cross(pole_ecliptic, sun_ecliptic);
  const glm::dvec3 sun = glm::normalize(sun_direction);
  const glm::dvec3 pole = DefaultEclipticPole(sun);
  const glm::dvec3 third = glm::cross(pole, sun);
  // Ecliptic -> local maps each of the three to its place: M = L E^T with orthonormal columns.
  const glm::dmat3 local_basis(sun, pole, third);
  const glm::dmat3 ecliptic_basis(sun_ecliptic, pole_ecliptic, third_ecliptic);
  const glm::dmat3 ecliptic_to_local = local_basis * glm::transpose(ecliptic_basis);
  // Equatorial -> ecliptic: a turn by the obliquity about x.
  const double c = std::cos(epsilon), s = std::sin(epsilon);
  const glm::dmat3 equatorial_to_ecliptic(1, 0, 0, 0, c, -s, 0, s, c);  // columns
  CelestialFrame frame;
  frame.to_local_ = ecliptic_to_local * equatorial_to_ecliptic;
  return frame;
}

glm::dvec3 CelestialFrame::ToLocal(const Star& star) const {
  const double years = (julian_day_utc_ - 2451545.0) / 365.25;
  return to_local_ * glm::normalize(star.direction + years * star.motion_per_yr);
}

glm::dvec3 CelestialFrame::EclipticPole() const {
  // The J2000 ecliptic's pole in J2000 coordinates (its motion since, 47" a century, is left out).
  const double epsilon = MeanObliquity(2451545.0);
  return glm::normalize(to_local_ * glm::dvec3(0.0, -std::sin(epsilon), std::cos(epsilon)));
}

double StarTemperatureK(double b_v) {
  const double x = std::clamp(b_v, -0.4, 2.0);
  return 4600.0 * (1.0 / (0.92 * x + 1.70) + 1.0 / (0.92 * x + 0.62));
}

void StarRelativeIrradiance(const Star& star, std::span<const double> wavelengths_nm, std::span<double> out) {
  const double temperature = StarTemperatureK(star.b_v);
  const auto planck = [temperature](double nm) {
    const double lambda = nm * 1e-9;
    return 1.0 / (std::pow(lambda, 5.0) * std::expm1(1.438776877e-2 / (lambda * temperature)));
  };
  // V = 0: 3.631e-11 W m^-2 nm^-1 at the V band's 545 nm.
  const double at_545 = 3.631e-11 * std::pow(10.0, -0.4 * star.v_mag);
  const double norm = at_545 / planck(545.0);
  for (std::size_t c = 0; c < wavelengths_nm.size() && c < out.size(); ++c) {
    out[c] = norm * planck(wavelengths_nm[c]) / SolarSpectralIrradiance(wavelengths_nm[c]);
  }
}

}  // namespace atmo
