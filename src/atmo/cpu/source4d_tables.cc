#include "cpu/source4d_tables.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/enumerable_thread_specific.h>
#include <oneapi/tbb/parallel_for.h>

#include "atmo/error.h"
#include "cpu/hillaire_tables.h"
#include "cpu/vector_math.h"
#include "models/model_options.h"

namespace atmo::cpu {
namespace {

using Clock = std::chrono::steady_clock;

constexpr int kSubSamples = 4;  // per cell and axis, for the quadrature matrices
constexpr double kLogFloor = 1e-30;

double NodeAngle(int i, int n, double range) { return range * i / (n - 1); }

// The incident radiance of one order on the gathering grid: values[ab * columns + column], with
// column = (i * mu_s_size + j) * 3 + channel for node (r_i, theta_s_j).
struct GatherField {
  int in_count = 0;
  int columns = 0;
  std::vector<float> values;
};

struct Grid {
  const shared::AtmosphereParameters& atmosphere;
  const Source4dSettings& s;
  int nodes() const { return s.r_size * s.mu_s_size; }
  double r(int i) const { return shared::GetSource4dRFromUnit(atmosphere, double(i) / (s.r_size - 1)); }
  double mu_s(int j) const {
    return std::cos(shared::GetSource4dSunZenithFromUnit(double(j) / (s.mu_s_size - 1), s.mu_s_size));
  }
};

// 1D table of a ground irradiance over the table's sun-zenith nodes.
shared::Texture2D IrradianceTable(const std::vector<glm::dvec3>& e) {
  shared::Texture2D t(static_cast<int>(e.size()), 1);
  for (std::size_t j = 0; j < e.size(); ++j) t.at(static_cast<int>(j), 0) = glm::vec3(e[j]);
  return t;
}

// Integrates one order along every gathering ray. order == 1: single scattering and the
// reflection of the direct sun; otherwise the table of that order and the reflection of the
// previous order's ground irradiance.
GatherField GatherRadiance(const Grid& grid, const shared::Texture2D& transmittance,
                           const shared::Texture3D& rayleigh, const shared::Texture3D& mie,
                           const shared::Texture2D& previous_irradiance, int order) {
  const Source4dSettings& s = grid.s;
  const auto& atmosphere = grid.atmosphere;
  GatherField field;
  field.in_count = s.gather_zeniths * s.gather_azimuths;
  field.columns = grid.nodes() * 3;
  field.values.assign(static_cast<std::size_t>(field.in_count) * field.columns, 0.0f);
  const glm::dvec3 albedo_over_pi = atmosphere.ground_albedo / shared::kPi;
  const bool ground = atmosphere.ground_albedo != glm::dvec3(0.0);
  oneapi::tbb::parallel_for(0, grid.nodes(), [&](int node) {
    const int i = node / s.mu_s_size;
    const int j = node % s.mu_s_size;
    const double r = grid.r(i);
    const double mu_s = grid.mu_s(j);
    const double sin_s = std::sqrt(std::max(1.0 - mu_s * mu_s, 0.0));
    for (int a = 0; a < s.gather_zeniths; ++a) {
      const double theta = NodeAngle(a, s.gather_zeniths, shared::kPi);
      const double mu = std::cos(theta);
      const double sin_v = std::sin(theta);
      const bool hits_ground = shared::RayIntersectsGround(atmosphere, r, mu);
      for (int b = 0; b < s.gather_azimuths; ++b) {
        const double nu = shared::ClampCosine(mu * mu_s + sin_v * sin_s * std::cos(NodeAngle(b, s.gather_azimuths, shared::kPi)));
        glm::dvec3 path_transmittance;
        glm::dvec3 L = shared::IntegrateSource4dRadianceInside(
            atmosphere, transmittance, rayleigh, mie, s.mu_s_size, r, mu, mu_s, nu, hits_ground,
            std::numeric_limits<double>::infinity(), s.gather_samples, order == 1 ? 1.0 : 0.0, order == 1 ? 0.0 : 1.0,
            shared::GetSource4dGatherMiePhase(atmosphere, a, b, s.gather_zeniths, s.gather_azimuths, mu_s, nu),
            path_transmittance);
        if (hits_ground && ground) {
          const double t = shared::DistanceToBottomAtmosphereBoundary(atmosphere, r, mu);
          const double mu_s_ground = shared::ClampCosine((r * mu_s + t * nu) / atmosphere.bottom_radius);
          glm::dvec3 e;
          if (order == 1) {
            e = mu_s_ground > 0.0 ? mu_s_ground * shared::GetTransmittanceToSun(atmosphere, transmittance,
                                                                                 atmosphere.bottom_radius, mu_s_ground)
                                  : glm::dvec3(0.0);
          } else {
            e = shared::GetSource4dGroundIrradiance(previous_irradiance, mu_s_ground);
          }
          L += path_transmittance * albedo_over_pi * e;
        }
        const std::size_t row = static_cast<std::size_t>(a * s.gather_azimuths + b) * field.columns;
        for (int c = 0; c < 3; ++c) field.values[row + static_cast<std::size_t>(node) * 3 + c] = static_cast<float>(L[c]);
      }
    }
  });
  return field;
}

// One step of a gathering ray without the planet's shadow: the steps of
// shared::IntegrateSource4dRadianceInside when no shadow edge lies on the ray (segments at the
// ray's lowest point only), with what does not depend on the sun.
struct Step {
  double t, r, mu;
  double y = 0.0, layer = 0.0;             // the table's view-zenith coordinate and r layer position
  glm::dvec3 weight_rayleigh, weight_mie;  // throughput x step integral x scattering coefficient
};

std::vector<Step> RaySteps(const shared::AtmosphereParameters& atmosphere, double r, double mu, bool hits_ground,
                           int sample_count, glm::dvec3& transmittance) {
  std::vector<Step> steps;
  transmittance = glm::dvec3(1.0);
  const double t_max = shared::DistanceToNearestAtmosphereBoundary(atmosphere, r, mu, hits_ground);
  if (!(t_max > 0.0)) return steps;
  const double t_low = -r * mu;
  double breaks[2];
  int break_count = 0;
  if (t_low > 0.0 && t_low < t_max) breaks[break_count++] = t_low;
  breaks[break_count++] = t_max;
  const int per_segment = std::max(2, (sample_count + break_count - 1) / break_count);
  double t_a = 0.0;
  for (int k = 0; k < break_count; ++k) {
    const double t_b = breaks[k];
    const bool dense_at_a = !(t_b <= t_low);
    for (int n = 0; n < per_segment; ++n) {
      const double t_0 = shared::GetSource4dStep(t_a, t_b, dense_at_a, n, per_segment);
      const double t_1 = shared::GetSource4dStep(t_a, t_b, dense_at_a, n + 1, per_segment);
      const double dt = t_1 - t_0;
      const double t = 0.5 * (t_0 + t_1);
      const double r_t = std::sqrt(std::max(t * t + 2.0 * r * mu * t + r * r, 0.0));
      const double mu_t = shared::ClampCosine((r * mu + t) / r_t);
      const shared::MediumSample medium = shared::SampleMedium(atmosphere, r_t);
      const glm::dvec3 step_transmittance = glm::exp(-medium.extinction * dt);
      const glm::dvec3 weight = transmittance * shared::IntegrateStep(medium.extinction, step_transmittance, dt);
      Step step;
      step.t = t;
      step.r = r_t;
      step.mu = mu_t;
      step.weight_rayleigh = weight * medium.rayleigh_scattering;
      step.weight_mie = weight * medium.mie_scattering;
      steps.push_back(step);
      transmittance *= step_transmittance;
    }
    t_a = std::max(t_a, t_b);
  }
  return steps;
}

// The lanes of one lookup in the sun loop of GatherMultipleRadiance: ln G_R (3 channels), ln G_M
// (3), two unused (finite, with weight 0), so that each texel of a slice is one 8-float vector.
constexpr int kLanes = 8;

// shared::GetSource4dUnitSunZenith and shared::GetSource4dAzimuth (radians, 0..pi) in float, with
// their branches as selects, for the sun loop of the orders >= 2 (twice the lanes of double per
// vector): shared::Source4dAcos's polynomial and the axis's knots rounded to float. The sun-zenith
// row and azimuth differ from double ones by ~1e-7 units (~1e-5 rows), which moves the gathered
// field by up to 1.1e-4 relative on a coarse grid where ln G changes fastest between rows
// (tests/source4d_test.cc) and rendered images by < 1e-6.
struct SunAxisFloat {
  float unit_1, unit_2, unit_3;
  float knot_1 = static_cast<float>(shared::kSource4dSunKnot1);
  float knot_2 = static_cast<float>(shared::kSource4dSunKnot2);
  float knot_3 = static_cast<float>(shared::kSource4dSunKnot3);
  float max_zenith = static_cast<float>(shared::kSource4dMaxSunZenith);
};

inline float AcosFloat(float x) {
  const float a = std::min(std::fabs(x), 1.0f);
  float p = -0.0012624911f;
  p = p * a + 0.0066700901f;
  p = p * a - 0.0170881256f;
  p = p * a + 0.0308918810f;
  p = p * a - 0.0501743046f;
  p = p * a + 0.0889789874f;
  p = p * a - 0.2145988016f;
  p = p * a + 1.5707963050f;
  const float angle = std::sqrt(1.0f - a) * p;
  return x < 0.0f ? 3.14159265358979f - angle : angle;
}

inline float LerpFloat(float x, float x_0, float x_1, float y_0, float y_1) {
  return y_0 + (y_1 - y_0) * (x - x_0) / (x_1 - x_0);
}

inline float SunUnitFloat(float mu_s, const SunAxisFloat& axis) {
  const float theta = AcosFloat(mu_s);
  const float u_0 = LerpFloat(theta, 0.0f, axis.knot_1, 0.0f, axis.unit_1);
  const float u_1 = LerpFloat(theta, axis.knot_1, axis.knot_2, axis.unit_1, axis.unit_2);
  const float u_2 = LerpFloat(theta, axis.knot_2, axis.knot_3, axis.unit_2, axis.unit_3);
  const float u_3 = std::min(LerpFloat(theta, axis.knot_3, axis.max_zenith, axis.unit_3, 1.0f), 1.0f);
  return theta < axis.knot_1 ? u_0 : theta < axis.knot_2 ? u_1 : theta < axis.knot_3 ? u_2 : u_3;
}

inline float AzimuthFloat(float mu, float mu_s, float nu) {
  const float s = std::sqrt(std::max((1.0f - mu * mu) * (1.0f - mu_s * mu_s), 0.0f));
  const float c = (nu - mu * mu_s) / std::max(s, 1e-9f);
  const float angle = AcosFloat(c < -1.0f ? -1.0f : (c > 1.0f ? 1.0f : c));
  return s > 1e-9f ? angle : 0.0f;
}

// The 2D slice of both tables at one step of a gathering ray: the step's view-zenith coordinate y
// and r layer position are the same for every sun node, so the two r layers and two view-zenith
// texels are blended once per step, leaving a bilinear lookup in (sun-zenith row, azimuth) per
// sun node. slice[(row * phi_size + x) * kLanes + lane]: lanes 0-2 ln G_R, 3-5 ln G_M, 6 a finite
// value that the sun loop weights by 0, 7 left as it is (0).
void Slice(const shared::Texture3D& rayleigh, const shared::Texture3D& mie, int mu_s_size, double y, double layer,
           std::vector<float>& slice) {
  int y_0, y_1;
  double wy;
  shared::detail::LinearTaps(y, rayleigh.height, false, y_0, y_1, wy);
  const int r_size = rayleigh.depth / mu_s_size;
  const int layer_0 = static_cast<int>(std::min(std::floor(layer), double(r_size - 2)));
  const float fy = static_cast<float>(wy);
  const float fl = static_cast<float>(layer - layer_0);
  const int width = rayleigh.width;
  const std::size_t plane = static_cast<std::size_t>(width) * rayleigh.height;
  static_assert(sizeof(glm::vec3) == 3 * sizeof(float), "vec3 arrays are packed floats");
  // glm::mix's formula, x (1 - a) + y a, on four floats from each tap at once (one 128-bit vector
  // on every target: the compilers' vector extension, which WebAssembly's clang does not otherwise
  // choose here): a texel's three and its neighbour's first. The Rayleigh texel goes to lanes 0-3,
  // then the Mie texel to lanes 3-6, replacing lane 3.
  typedef float Float4 __attribute__((vector_size(16)));
  const auto load = [](const float* p) {
    Float4 v;
    std::memcpy(&v, p, sizeof v);
    return v;
  };
  const auto blend = [fy, fl, &load](const float* a, const float* b, const float* c, const float* d, float* out) {
    const Float4 lower = load(a) * (1.0f - fy) + load(b) * fy;
    const Float4 upper = load(c) * (1.0f - fy) + load(d) * fy;
    const Float4 v = lower * (1.0f - fl) + upper * fl;
    std::memcpy(out, &v, sizeof v);
  };
  for (int k = 0; k < mu_s_size; ++k) {
    const std::size_t z_0 = static_cast<std::size_t>(layer_0 * mu_s_size + k) * plane;
    const std::size_t z_1 = z_0 + static_cast<std::size_t>(mu_s_size) * plane;
    const std::size_t taps[] = {z_0 + static_cast<std::size_t>(y_0) * width, z_0 + static_cast<std::size_t>(y_1) * width,
                                z_1 + static_cast<std::size_t>(y_0) * width, z_1 + static_cast<std::size_t>(y_1) * width};
    float* out = slice.data() + static_cast<std::size_t>(k) * width * kLanes;
    const float* r[4];
    const float* m[4];
    for (int tap = 0; tap < 4; ++tap) {
      r[tap] = &rayleigh.texels[taps[tap]].x;
      m[tap] = &mie.texels[taps[tap]].x;
    }
    // A row's last texel reads the next row's first float, except at a table's end, where it
    // takes copies with a fourth float of 0 (taps[3] is the furthest tap).
    const bool last_in_memory = (taps[3] + width) * 3 + 1 <= 3 * std::min(rayleigh.texels.size(), mie.texels.size());
    const int vector_texels = last_in_memory ? width : width - 1;
    for (int x = 0; x < vector_texels; ++x) {
      blend(r[0] + 3 * x, r[1] + 3 * x, r[2] + 3 * x, r[3] + 3 * x, out + x * kLanes);
      blend(m[0] + 3 * x, m[1] + 3 * x, m[2] + 3 * x, m[3] + 3 * x, out + x * kLanes + 3);
    }
    if (!last_in_memory) {
      const int x = width - 1;
      for (int table = 0; table < 2; ++table) {
        float last[4][4] = {};
        for (int tap = 0; tap < 4; ++tap) {
          for (int ch = 0; ch < 3; ++ch) last[tap][ch] = (table == 0 ? r : m)[tap][3 * x + ch];
        }
        blend(last[0], last[1], last[2], last[3], out + x * kLanes + 3 * table);
      }
    }
  }
}

// Per-thread buffers of the sun loop.
struct SunScratch {
  std::vector<double> r_mu_s, nu;  // per pair (sun node j, azimuth b)
  std::vector<float> r_mu_s_f, nu_f;  // the same in float, for the coordinates
  std::vector<int> base;           // per pair: the slice index of its first tap
  std::vector<float> w_row, w_x;   // per pair: the taps' weights
  std::vector<float> sum;          // per batch and pair, kLanes: sum[(batch * pairs + p) * kLanes + lane]
  std::vector<float> slice;        // one batch's at a time
  void Resize(int pairs, int slice_texels, std::size_t batches) {
    r_mu_s.resize(pairs);
    nu.resize(pairs);
    r_mu_s_f.resize(pairs);
    nu_f.resize(pairs);
    base.resize(pairs);
    w_row.resize(pairs);
    w_x.resize(pairs);
    sum.resize(batches * static_cast<std::size_t>(pairs) * kLanes);
    slice.resize(static_cast<std::size_t>(slice_texels) * kLanes);
  }
};

// GatherRadiance for an order n >= 2 (the table's orders alone, no single scattering), with the
// work that does not depend on the sun done once per ray: a ray of given (r_i, theta'_a) has the
// same steps, media, throughputs and view-zenith and layer coordinates for every sun zenith and
// azimuth of the grid; only the sun's coordinates and the lookups differ. The steps are those of
// shared::IntegrateSource4dRadianceInside with single_weight = 0 (tests/source4d_test.cc checks
// that the two agree). Per step the tables are reduced to a 2D slice (Slice), and the sun loop
// runs over all (sun node, azimuth) pairs of the ray at once: their coordinates in float (once
// for every batch), then each batch's bilinear lookups, exp (ExpFloat) and weighted sums in
// 8-float vectors. fields[k] is batch k's, as if it had been gathered alone.
std::vector<GatherField> GatherMultipleRadiance(std::span<const Grid> grids,
                                                std::span<const shared::Texture3D* const> rayleigh,
                                                std::span<const shared::Texture3D* const> mie,
                                                std::span<const shared::Texture2D* const> previous_irradiance) {
  const std::size_t batches = grids.size();
  const Grid& grid = grids.front();  // the geometry of every batch
  const Source4dSettings& s = grid.s;
  const auto& atmosphere = grid.atmosphere;
  std::vector<GatherField> fields(batches);
  for (GatherField& field : fields) {
    field.in_count = s.gather_zeniths * s.gather_azimuths;
    field.columns = grid.nodes() * 3;
    field.values.assign(static_cast<std::size_t>(field.in_count) * field.columns, 0.0f);
  }
  std::vector<double> sun_mu_s(s.mu_s_size), sun_sin_s(s.mu_s_size), azimuth_cos(s.gather_azimuths);
  for (int j = 0; j < s.mu_s_size; ++j) {
    sun_mu_s[j] = grid.mu_s(j);
    sun_sin_s[j] = std::sqrt(std::max(1.0 - sun_mu_s[j] * sun_mu_s[j], 0.0));
  }
  for (int b = 0; b < s.gather_azimuths; ++b) azimuth_cos[b] = std::cos(NodeAngle(b, s.gather_azimuths, shared::kPi));
  oneapi::tbb::enumerable_thread_specific<SunScratch> scratch;
  oneapi::tbb::parallel_for(0, s.r_size * s.gather_zeniths, [&](int ray) {
    const int i = ray / s.gather_zeniths;
    const int a = ray % s.gather_zeniths;
    const double r = grid.r(i);
    const double theta = NodeAngle(a, s.gather_zeniths, shared::kPi);
    const double mu = std::cos(theta);
    const double sin_v = std::sin(theta);
    const bool hits_ground = shared::RayIntersectsGround(atmosphere, r, mu);
    // The steps of every batch: the same points, each batch's media and throughputs.
    std::vector<std::vector<Step>> steps(batches);
    std::vector<glm::dvec3> transmittance(batches);
    for (std::size_t k = 0; k < batches; ++k) {
      steps[k] = RaySteps(grids[k].atmosphere, r, mu, hits_ground, s.gather_samples, transmittance[k]);
    }
    for (Step& step : steps[0]) {
      step.y = shared::GetSource4dZenithCoord(*rayleigh[0], step.mu);
      step.layer = shared::GetSource4dLayer(atmosphere, *rayleigh[0], s.mu_s_size, step.r);
    }
    const double t_ground = hits_ground ? shared::DistanceToBottomAtmosphereBoundary(atmosphere, r, mu) : 0.0;
    // The (sun zenith j, azimuth b) pairs of this ray: r mu_s and nu.
    const int pairs = s.mu_s_size * s.gather_azimuths;
    SunScratch& w = scratch.local();
    w.Resize(pairs, s.mu_s_size * s.phi_size, batches);
    for (int j = 0; j < s.mu_s_size; ++j) {
      for (int b = 0; b < s.gather_azimuths; ++b) {
        const int p = j * s.gather_azimuths + b;
        w.r_mu_s[p] = r * sun_mu_s[j];
        w.nu[p] = shared::ClampCosine(mu * sun_mu_s[j] + sin_v * sun_sin_s[j] * azimuth_cos[b]);
        w.r_mu_s_f[p] = static_cast<float>(w.r_mu_s[p]);
        w.nu_f[p] = static_cast<float>(w.nu[p]);
      }
    }
    std::fill(w.sum.begin(), w.sum.end(), 0.0f);
    const shared::Source4dSunAxis axis = shared::GetSource4dSunAxis(s.mu_s_size);
    SunAxisFloat sun_axis;
    sun_axis.unit_1 = static_cast<float>(axis.unit_1);
    sun_axis.unit_2 = static_cast<float>(axis.unit_2);
    sun_axis.unit_3 = static_cast<float>(axis.unit_3);
    for (std::size_t n = 0; n < steps[0].size(); ++n) {
      const Step& step = steps[0][n];
      // Every pair's sun-zenith row and azimuth at this step (vectorised, in float), for every
      // batch.
      const float inv_r = static_cast<float>(1.0 / step.r);
      const float mu_t = static_cast<float>(step.mu);
      const float row_scale = static_cast<float>(s.mu_s_size - 1);
      const float azimuth_scale = static_cast<float>((s.phi_size - 1) / shared::kPi);
      const float t = static_cast<float>(step.t);
      const int last_row = s.mu_s_size - 2;
      const int last_x = s.phi_size - 2;
      const int phi_size = s.phi_size;
      const float* __restrict r_mu_s = w.r_mu_s_f.data();
      const float* __restrict nu = w.nu_f.data();
      int* __restrict base = w.base.data();
      float* __restrict w_row = w.w_row.data();
      float* __restrict w_x = w.w_x.data();
      for (int p = 0; p < pairs; ++p) {
        const float c = (r_mu_s[p] + t * nu[p]) * inv_r;
        const float mu_s_t = c < -1.0f ? -1.0f : (c > 1.0f ? 1.0f : c);
        const float row = SunUnitFloat(mu_s_t, sun_axis) * row_scale;
        const float azimuth = AzimuthFloat(mu_t, mu_s_t, nu[p]) * azimuth_scale;
        const int row_0 = std::min(static_cast<int>(row), last_row);
        const int x_0 = std::min(static_cast<int>(azimuth), last_x);
        base[p] = (row_0 * phi_size + x_0) * kLanes;
        w_row[p] = row - static_cast<float>(row_0);
        w_x[p] = azimuth - static_cast<float>(x_0);
      }
      const int row_stride = s.phi_size * kLanes;
      for (std::size_t k = 0; k < batches; ++k) {
        Slice(*rayleigh[k], *mie[k], s.mu_s_size, step.y, step.layer, w.slice);
        float weights[kLanes] = {};
        for (int c = 0; c < 3; ++c) {
          weights[c] = static_cast<float>(steps[k][n].weight_rayleigh[c]);
          weights[3 + c] = static_cast<float>(steps[k][n].weight_mie[c]);
        }
        float* batch_sum = w.sum.data() + k * static_cast<std::size_t>(pairs) * kLanes;
        for (int p = 0; p < pairs; ++p) {
          const float* q = w.slice.data() + w.base[p];
          const float fx = w.w_x[p];
          const float fr = w.w_row[p];
          float* sum = batch_sum + static_cast<std::size_t>(p) * kLanes;
          // One vector of lanes (GCC vectorises it as it is; clang's cost model for WebAssembly
          // does not without the pragma, which made the web build's gathers 4x slower).
#pragma omp simd
          for (int l = 0; l < kLanes; ++l) {
            const float low = q[l] + (q[kLanes + l] - q[l]) * fx;
            const float high = q[row_stride + l] + (q[row_stride + kLanes + l] - q[row_stride + l]) * fx;
            sum[l] += weights[l] * ExpFloat(low + (high - low) * fr);
          }
        }
      }
    }
    for (std::size_t k = 0; k < batches; ++k) {
      const shared::AtmosphereParameters& batch = grids[k].atmosphere;
      const glm::dvec3 albedo_over_pi = batch.ground_albedo / shared::kPi;
      const bool ground = batch.ground_albedo != glm::dvec3(0.0);
      const float* batch_sum = w.sum.data() + k * static_cast<std::size_t>(pairs) * kLanes;
      GatherField& field = fields[k];
      for (int j = 0; j < s.mu_s_size; ++j) {
        const int node = i * s.mu_s_size + j;
        for (int b = 0; b < s.gather_azimuths; ++b) {
          const int p = j * s.gather_azimuths + b;
          const float* sum = batch_sum + static_cast<std::size_t>(p) * kLanes;
          glm::dvec3 L(double(sum[0]) + sum[3], double(sum[1]) + sum[4], double(sum[2]) + sum[5]);
          if (hits_ground && ground) {
            const double mu_s_ground = shared::ClampCosine((w.r_mu_s[p] + t_ground * w.nu[p]) / batch.bottom_radius);
            L += transmittance[k] * albedo_over_pi * shared::GetSource4dGroundIrradiance(*previous_irradiance[k], mu_s_ground);
          }
          const std::size_t row = static_cast<std::size_t>(a * s.gather_azimuths + b) * field.columns;
          for (int c = 0; c < 3; ++c) field.values[row + static_cast<std::size_t>(node) * 3 + c] = static_cast<float>(L[c]);
        }
      }
    }
  });
  return fields;
}

// Per-thread buffers of GatherSingleRadiance, per (sun node, azimuth) pair of a ray.
struct SingleScratch {
  std::vector<double> r_mu_s, nu, rayleigh_phase, mie_phase;
  std::vector<char> shared_steps;
  std::vector<glm::dvec3> sum, path_transmittance;  // per batch and pair: [batch * pairs + p]
  std::vector<int> x_0;  // per step: the transmittance table's column tap and weight, lit or not
  std::vector<double> w_x, lit;
  void Resize(int pairs, std::size_t batches) {
    for (std::vector<double>* v : {&r_mu_s, &nu, &rayleigh_phase, &mie_phase, &w_x, &lit}) v->resize(pairs);
    shared_steps.resize(pairs);
    sum.resize(batches * pairs);
    path_transmittance.resize(batches * pairs);
    x_0.resize(pairs);
  }
};

// GatherRadiance for order 1 with the sun-independent work done once per ray where it can be: a
// (sun node, azimuth) pair whose ray has no shadow edge on it (the sun up at every step, or the
// whole ray in the planet's shadow) has exactly the ray's shadow-free steps, and only the sun's
// transmittance and the phase functions differ per pair; the other pairs take the general march,
// whose steps end at the shadow's edges (tests/source4d_test.cc checks that the two agree).
std::vector<GatherField> GatherSingleRadiance(std::span<const Grid> grids,
                                              std::span<const shared::Texture2D* const> transmittance_tables) {
  const std::size_t batches = grids.size();
  const Grid& grid = grids.front();  // the geometry and phase functions of every batch
  const Source4dSettings& s = grid.s;
  const auto& atmosphere = grid.atmosphere;
  std::vector<GatherField> fields(batches);
  for (GatherField& field : fields) {
    field.in_count = s.gather_zeniths * s.gather_azimuths;
    field.columns = grid.nodes() * 3;
    field.values.assign(static_cast<std::size_t>(field.in_count) * field.columns, 0.0f);
  }
  const shared::Texture3D no_table;
  std::vector<double> sun_mu_s(s.mu_s_size), sun_sin_s(s.mu_s_size), azimuth_cos(s.gather_azimuths);
  for (int j = 0; j < s.mu_s_size; ++j) {
    sun_mu_s[j] = grid.mu_s(j);
    sun_sin_s[j] = std::sqrt(std::max(1.0 - sun_mu_s[j] * sun_mu_s[j], 0.0));
  }
  for (int b = 0; b < s.gather_azimuths; ++b) azimuth_cos[b] = std::cos(NodeAngle(b, s.gather_azimuths, shared::kPi));
  const double bottom = atmosphere.bottom_radius;
  const double top = atmosphere.top_radius;
  const double top_rho = std::sqrt((top - bottom) * (top + bottom));  // H of the transmittance mapping
  const shared::Texture2D& first_table = *transmittance_tables[0];
  oneapi::tbb::enumerable_thread_specific<SingleScratch> scratch;
  oneapi::tbb::parallel_for(0, s.r_size * s.gather_zeniths, [&](int ray) {
    const int i = ray / s.gather_zeniths;
    const int a = ray % s.gather_zeniths;
    const double r = grid.r(i);
    const double theta = NodeAngle(a, s.gather_zeniths, shared::kPi);
    const double mu = std::cos(theta);
    const double sin_v = std::sin(theta);
    const bool hits_ground = shared::RayIntersectsGround(atmosphere, r, mu);
    const double t_max = shared::DistanceToNearestAtmosphereBoundary(atmosphere, r, mu, hits_ground);
    const double t_ground = hits_ground ? shared::DistanceToBottomAtmosphereBoundary(atmosphere, r, mu) : 0.0;
    // The steps of every batch: the same points, each batch's media and throughputs.
    std::vector<std::vector<Step>> steps(batches);
    std::vector<glm::dvec3> ray_transmittance(batches);
    for (std::size_t k = 0; k < batches; ++k) {
      steps[k] = RaySteps(grids[k].atmosphere, r, mu, hits_ground, s.gather_samples, ray_transmittance[k]);
    }
    const int pairs = s.mu_s_size * s.gather_azimuths;
    SingleScratch& w = scratch.local();
    w.Resize(pairs, batches);
    // Per pair: nu, and whether it shares the ray's steps (else: the general march of each
    // batch, now).
    for (int j = 0; j < s.mu_s_size; ++j) {
      const double mu_s = sun_mu_s[j];
      for (int b = 0; b < s.gather_azimuths; ++b) {
        const int p = j * s.gather_azimuths + b;
        const double nu = shared::ClampCosine(mu * mu_s + sin_v * sun_sin_s[j] * azimuth_cos[b]);
        w.r_mu_s[p] = r * mu_s;
        w.nu[p] = nu;
        double shadow_0, shadow_1;
        const bool shadow = t_max > 0.0 && shared::GetSource4dShadowInterval(atmosphere, r, mu, mu_s, nu, t_max,
                                                                             shadow_0, shadow_1);
        w.shared_steps[p] = !shadow || (!(shadow_0 > 0.0) && !(shadow_1 < t_max));
        const double mie_phase =
            shared::GetSource4dGatherMiePhase(atmosphere, a, b, s.gather_zeniths, s.gather_azimuths, mu_s, nu);
        if (w.shared_steps[p]) {
          w.rayleigh_phase[p] = shared::GetRayleighPhase(atmosphere, nu);
          w.mie_phase[p] = mie_phase;
        }
        for (std::size_t k = 0; k < batches; ++k) {
          const std::size_t kp = k * static_cast<std::size_t>(pairs) + p;
          w.path_transmittance[kp] = ray_transmittance[k];
          w.sum[kp] = w.shared_steps[p] ? glm::dvec3(0.0)
                                        : shared::IntegrateSource4dRadianceInside(
                                              grids[k].atmosphere, *transmittance_tables[k], no_table, no_table,
                                              s.mu_s_size, r, mu, mu_s, nu, hits_ground,
                                              std::numeric_limits<double>::infinity(), s.gather_samples, 1.0, 0.0,
                                              mie_phase, w.path_transmittance[kp]);
        }
      }
    }
    // The shared steps: per step the transmittance table's row taps (the step's r), then every
    // pair's column tap (vectorised) and each batch's lookup: shared::GetTransmittanceToSun,
    // reorganised.
    const int width = first_table.width;
    for (std::size_t n = 0; n < steps[0].size(); ++n) {
      const Step& step = steps[0][n];
      const double r_t = step.r;
      const double rho = std::sqrt(std::max((r_t - bottom) * (r_t + bottom), 0.0));
      const double d_min = top - r_t;
      const double d_max = rho + top_rho;
      int y_0, y_1;
      double wy;
      shared::detail::LinearTaps(shared::GetTextureCoordFromUnitRange(rho / top_rho, first_table.height),
                                 first_table.height, false, y_0, y_1, wy);
      const double c_top = (top - r_t) * (top + r_t);
      const double c_bottom = (bottom - r_t) * (bottom + r_t);
      const double inv_r = 1.0 / r_t;
      const double t = step.t;
      const double column_scale = (width - 1) / (d_max - d_min);
      const double last_column = width - 1;
      const int last_x = width - 2;
      const double* __restrict r_mu_s = w.r_mu_s.data();
      const double* __restrict nu = w.nu.data();
      int* __restrict x_0 = w.x_0.data();
      double* __restrict w_x = w.w_x.data();
      double* __restrict lit = w.lit.data();
      for (int p = 0; p < pairs; ++p) {
        const double mu_s_t = shared::ClampCosine((r_mu_s[p] + t * nu[p]) * inv_r);
        const double r_mu = r_t * mu_s_t;
        const double root = std::sqrt(std::max(c_top + r_mu * r_mu, 0.0));
        const double d = std::max(mu_s_t > 0.0 ? c_top / (r_mu + root) : -r_mu + root, 0.0);
        const double column = std::clamp((d - d_min) * column_scale, 0.0, last_column);
        const int x = std::min(static_cast<int>(column), last_x);
        x_0[p] = x;
        w_x[p] = column - x;
        lit[p] = mu_s_t < 0.0 && c_bottom + r_mu * r_mu >= 0.0 ? 0.0 : 1.0;  // below the horizon: 0
      }
      for (std::size_t k = 0; k < batches; ++k) {
        const shared::Texture2D& table = *transmittance_tables[k];
        const glm::vec3* row_0 = table.texels.data() + static_cast<std::size_t>(y_0) * width;
        const glm::vec3* row_1 = table.texels.data() + static_cast<std::size_t>(y_1) * width;
        const Step& batch_step = steps[k][n];
        glm::dvec3* sum = w.sum.data() + k * static_cast<std::size_t>(pairs);
        for (int p = 0; p < pairs; ++p) {
          if (!w.shared_steps[p] || lit[p] == 0.0) continue;
          const int x = x_0[p];
          const glm::dvec3 low = glm::mix(glm::dvec3(row_0[x]), glm::dvec3(row_0[x + 1]), w_x[p]);
          const glm::dvec3 high = glm::mix(glm::dvec3(row_1[x]), glm::dvec3(row_1[x + 1]), w_x[p]);
          sum[p] += glm::mix(low, high, wy) *
                    (batch_step.weight_rayleigh * w.rayleigh_phase[p] + batch_step.weight_mie * w.mie_phase[p]);
        }
      }
    }
    for (std::size_t k = 0; k < batches; ++k) {
      const shared::AtmosphereParameters& batch = grids[k].atmosphere;
      const glm::dvec3 albedo_over_pi = batch.ground_albedo / shared::kPi;
      const bool ground = batch.ground_albedo != glm::dvec3(0.0);
      GatherField& field = fields[k];
      for (int j = 0; j < s.mu_s_size; ++j) {
        const double mu_s = sun_mu_s[j];
        const int node = i * s.mu_s_size + j;
        for (int b = 0; b < s.gather_azimuths; ++b) {
          const int p = j * s.gather_azimuths + b;
          const std::size_t kp = k * static_cast<std::size_t>(pairs) + p;
          glm::dvec3 L = w.sum[kp];
          if (hits_ground && ground) {
            const double mu_s_ground = shared::ClampCosine((r * mu_s + t_ground * w.nu[p]) / batch.bottom_radius);
            if (mu_s_ground > 0.0) {
              L += w.path_transmittance[kp] * albedo_over_pi * mu_s_ground *
                   shared::GetTransmittanceToSun(batch, *transmittance_tables[k], batch.bottom_radius, mu_s_ground);
            }
          }
          const std::size_t row = static_cast<std::size_t>(a * s.gather_azimuths + b) * field.columns;
          for (int c = 0; c < 3; ++c) field.values[row + static_cast<std::size_t>(node) * 3 + c] = static_cast<float>(L[c]);
        }
      }
    }
  });
  return fields;
}

// G_m[cd * columns + column] = sum over ab of W_m[cd][ab] field[ab][column], for both media in one
// pass. Blocked so that each row of the field, read once per block of kBlockRows output
// directions and kBlockColumns columns, serves both matrices and all rows of the block from the
// cache (the unblocked product read the whole field, 4 MB by default, once per output direction
// and medium); the sum over ab runs in the same order as unblocked, so the result is the same.
constexpr int kBlockRows = 4;
constexpr int kBlockColumns = 256;

void Convolve(const Source4dQuadrature& q, const GatherField& field, std::vector<float>& g_r,
              std::vector<float>& g_m) {
  const int out_count = q.out_count;
  const bool low_rank = !q.rayleigh_out.empty();
  g_r.resize(static_cast<std::size_t>(out_count) * field.columns);
  g_m.resize(g_r.size());
  const int row_blocks = (out_count + kBlockRows - 1) / kBlockRows;
  const int column_blocks = (field.columns + kBlockColumns - 1) / kBlockColumns;
  oneapi::tbb::parallel_for(0, row_blocks * column_blocks, [&](int block) {
    const int cd_0 = (block / column_blocks) * kBlockRows;
    const int rows = std::min(kBlockRows, out_count - cd_0);
    const int k_0 = (block % column_blocks) * kBlockColumns;
    const int width = std::min(kBlockColumns, field.columns - k_0);
    alignas(32) float sum[2][kBlockRows][kBlockColumns] = {};
    for (int ab = 0; ab < field.in_count; ++ab) {
      const float* in = field.values.data() + static_cast<std::size_t>(ab) * field.columns + k_0;
      for (int m = low_rank ? 1 : 0; m < 2; ++m) {
        const std::vector<float>& w = m == 0 ? q.rayleigh : q.mie;
        for (int c = 0; c < rows; ++c) {
          const float weight = w[static_cast<std::size_t>(cd_0 + c) * field.in_count + ab];
          if (weight == 0.0f) continue;
          float* out = sum[m][c];
          for (int k = 0; k < width; ++k) out[k] += weight * in[k];
        }
      }
    }
    for (int m = low_rank ? 1 : 0; m < 2; ++m) {
      std::vector<float>& g = m == 0 ? g_r : g_m;
      for (int c = 0; c < rows; ++c) {
        std::copy(sum[m][c], sum[m][c] + width, g.data() + static_cast<std::size_t>(cd_0 + c) * field.columns + k_0);
      }
    }
  });
  if (!low_rank) return;
  // G_R = F (H L): the field projected on the five node functions, then each view's combination.
  const std::size_t columns = static_cast<std::size_t>(field.columns);
  std::vector<float> projected(static_cast<std::size_t>(kSource4dRayleighRank) * columns);
  oneapi::tbb::parallel_for(0, column_blocks, [&](int block) {
    const std::size_t k_0 = static_cast<std::size_t>(block) * kBlockColumns;
    const std::size_t width = std::min<std::size_t>(kBlockColumns, columns - k_0);
    alignas(32) float sum[kSource4dRayleighRank][kBlockColumns] = {};
    for (int ab = 0; ab < field.in_count; ++ab) {
      const float* in = field.values.data() + static_cast<std::size_t>(ab) * columns + k_0;
      for (int t = 0; t < kSource4dRayleighRank; ++t) {
        const float weight = q.rayleigh_in[static_cast<std::size_t>(t) * field.in_count + ab];
        for (std::size_t k = 0; k < width; ++k) sum[t][k] += weight * in[k];
      }
    }
    for (int t = 0; t < kSource4dRayleighRank; ++t) {
      std::copy(sum[t], sum[t] + width, projected.data() + static_cast<std::size_t>(t) * columns + k_0);
    }
  });
  oneapi::tbb::parallel_for(0, out_count, [&](int cd) {
    float* out = g_r.data() + static_cast<std::size_t>(cd) * columns;
    const float* f = q.rayleigh_out.data() + static_cast<std::size_t>(cd) * kSource4dRayleighRank;
    for (std::size_t k = 0; k < columns; ++k) {
      float v = 0.0f;
      for (int t = 0; t < kSource4dRayleighRank; ++t) v += f[t] * projected[static_cast<std::size_t>(t) * columns + k];
      out[k] = v;
    }
  });
}

// The ground node's irradiance from a field, per sun-zenith node.
std::vector<glm::dvec3> GroundIrradiance(const Grid& grid, const Source4dQuadrature& q, const GatherField& field) {
  std::vector<glm::dvec3> e(grid.s.mu_s_size, glm::dvec3(0.0));
  for (int ab = 0; ab < field.in_count; ++ab) {
    const double w = q.irradiance[ab];
    if (w == 0.0) continue;
    const float* in = field.values.data() + static_cast<std::size_t>(ab) * field.columns;
    for (int j = 0; j < grid.s.mu_s_size; ++j) {
      for (int c = 0; c < 3; ++c) e[j][c] += w * in[j * 3 + c];  // node i = 0: the ground
    }
  }
  return e;
}

// ln G into the table layout (x = azimuth d, y = zenith c, z = i * mu_s_size + j).
void WriteLogTable(const Grid& grid, const std::vector<float>& g, shared::Texture3D& table) {
  const Source4dSettings& s = grid.s;
  table = shared::Texture3D(s.phi_size, s.mu_size, grid.nodes());
  const int columns = grid.nodes() * 3;
  oneapi::tbb::parallel_for(0, grid.nodes(), [&](int node) {
    for (int c = 0; c < s.mu_size; ++c) {
      for (int d = 0; d < s.phi_size; ++d) {
        const float* v = g.data() + static_cast<std::size_t>(c * s.phi_size + d) * columns + node * 3;
        table.at(d, c, node) = glm::vec3(std::log(std::max(double(v[0]), kLogFloor)),
                                         std::log(std::max(double(v[1]), kLogFloor)),
                                         std::log(std::max(double(v[2]), kLogFloor)));
      }
    }
  });
}

}  // namespace

std::vector<float> GatherSource4dOrder(const shared::AtmosphereParameters& atmosphere, const Source4dSettings& settings,
                                       const Source4dTables& tables, int order, bool shared_geometry) {
  const Grid grid{atmosphere, settings};
  if (shared_geometry) {
    const std::span<const Grid> grids(&grid, 1);
    if (order == 1) {
      const shared::Texture2D* transmittance[] = {&tables.transmittance};
      return std::move(GatherSingleRadiance(grids, transmittance).front().values);
    }
    const shared::Texture3D* rayleigh[] = {&tables.rayleigh};
    const shared::Texture3D* mie[] = {&tables.mie};
    const shared::Texture2D* irradiance[] = {&tables.ground_irradiance};
    return std::move(GatherMultipleRadiance(grids, rayleigh, mie, irradiance).front().values);
  }
  return GatherRadiance(grid, tables.transmittance, tables.rayleigh, tables.mie, tables.ground_irradiance, order).values;
}

std::vector<double> ComputeSource4dIrradianceWeights(const Source4dSettings& s) {
  const int in_count = s.gather_zeniths * s.gather_azimuths;
  std::vector<double> irradiance(in_count, 0.0);
  const double d_theta = shared::kPi / (s.gather_zeniths - 1);
  const double d_phi = shared::kPi / (s.gather_azimuths - 1);
  // The sub-samples of every cell of the upper half (cos theta > 0), as the matrices' below: the
  // cosine-weighted solid angle of both mirror halves, spread over the cell's nodes by the hats.
  for (int a = 0; a + 1 < s.gather_zeniths; ++a) {
    for (int b = 0; b + 1 < s.gather_azimuths; ++b) {
      for (int u = 0; u < kSubSamples; ++u) {
        const double fu = (u + 0.5) / kSubSamples;
        const double theta = (a + fu) * d_theta;
        const double cos_theta = std::cos(theta);
        if (cos_theta <= 0.0) continue;
        for (int v = 0; v < kSubSamples; ++v) {
          const double fv = (v + 0.5) / kSubSamples;
          const double solid_angle = std::sin(theta) * d_theta * d_phi / (kSubSamples * kSubSamples);
          const int n00 = a * s.gather_azimuths + b;
          const int node[4] = {n00, n00 + s.gather_azimuths, n00 + 1, n00 + s.gather_azimuths + 1};
          const double hat[4] = {(1 - fu) * (1 - fv), fu * (1 - fv), (1 - fu) * fv, fu * fv};
          for (int k = 0; k < 4; ++k) irradiance[node[k]] += 2.0 * solid_angle * cos_theta * hat[k];
        }
      }
    }
  }
  double sum = 0.0;
  for (double w : irradiance) sum += w;
  for (double& w : irradiance) w *= shared::kPi / sum;  // a uniform unit radiance gives pi
  return irradiance;
}

Source4dQuadrature ComputeSource4dQuadrature(const shared::AtmosphereParameters& atmosphere,
                                             const Source4dSettings& s) {
  Source4dQuadrature q;
  q.out_count = s.mu_size * s.phi_size;
  q.in_count = s.gather_zeniths * s.gather_azimuths;
  q.rayleigh.assign(static_cast<std::size_t>(q.out_count) * q.in_count, 0.0f);
  q.mie.assign(q.rayleigh.size(), 0.0f);
  q.irradiance.assign(q.in_count, 0.0);
  const double d_theta = shared::kPi / (s.gather_zeniths - 1);
  const double d_phi = shared::kPi / (s.gather_azimuths - 1);
  // The sub-samples of every cell: direction, solid angle (both mirror halves together are
  // handled per output), and the four hat weights.
  struct SubSample {
    double cos_theta, sin_theta, phi, cos_phi, sin_phi, solid_angle;
    int node[4];
    double hat[4];
  };
  std::vector<SubSample> subs;
  for (int a = 0; a + 1 < s.gather_zeniths; ++a) {
    for (int b = 0; b + 1 < s.gather_azimuths; ++b) {
      for (int u = 0; u < kSubSamples; ++u) {
        for (int v = 0; v < kSubSamples; ++v) {
          const double fu = (u + 0.5) / kSubSamples;
          const double fv = (v + 0.5) / kSubSamples;
          const double theta = (a + fu) * d_theta;
          SubSample sub;
          sub.cos_theta = std::cos(theta);
          sub.sin_theta = std::sin(theta);
          sub.phi = (b + fv) * d_phi;
          sub.cos_phi = std::cos(sub.phi);
          sub.sin_phi = std::sin(sub.phi);
          sub.solid_angle = sub.sin_theta * d_theta * d_phi / (kSubSamples * kSubSamples);
          const int n00 = a * s.gather_azimuths + b;
          sub.node[0] = n00;
          sub.node[1] = n00 + s.gather_azimuths;
          sub.node[2] = n00 + 1;
          sub.node[3] = n00 + s.gather_azimuths + 1;
          sub.hat[0] = (1 - fu) * (1 - fv);
          sub.hat[1] = fu * (1 - fv);
          sub.hat[2] = (1 - fu) * fv;
          sub.hat[3] = fu * fv;
          subs.push_back(sub);
        }
      }
    }
  }
  q.irradiance = ComputeSource4dIrradianceWeights(s);
  // The Rayleigh phase function as A + B nu^2, where it is one (checked at six cosines).
  const double phase_a = shared::GetRayleighPhase(atmosphere, 0.0);
  const double phase_b = shared::GetRayleighPhase(atmosphere, 1.0) - phase_a;
  bool quadratic = phase_a > 0.0;
  for (double nu : {-1.0, -0.6, -0.2, 0.3, 0.7, 0.95}) {
    quadratic = quadratic && std::fabs(shared::GetRayleighPhase(atmosphere, nu) - (phase_a + phase_b * nu * nu)) <=
                                 1e-12 * phase_a;
  }
  // Its node functions, sum over a node's sub-samples of g_t(w) x solid angle x hat, with
  // g = (1, c^2, c s cos(phi), s^2 cos^2(phi), s^2 sin^2(phi)), c = cos(theta), s = sin(theta).
  std::vector<double> rayleigh_in(static_cast<std::size_t>(kSource4dRayleighRank) * q.in_count, 0.0);
  if (quadratic) {
    for (const SubSample& sub : subs) {
      const double c = sub.cos_theta;
      const double sn = sub.sin_theta;
      const double g[kSource4dRayleighRank] = {1.0, c * c, c * sn * sub.cos_phi, sn * sn * sub.cos_phi * sub.cos_phi,
                                               sn * sn * sub.sin_phi * sub.sin_phi};
      for (int t = 0; t < kSource4dRayleighRank; ++t) {
        for (int k = 0; k < 4; ++k) {
          rayleigh_in[static_cast<std::size_t>(t) * q.in_count + sub.node[k]] += g[t] * sub.solid_angle * sub.hat[k];
        }
      }
    }
    q.rayleigh_in.assign(rayleigh_in.begin(), rayleigh_in.end());
    q.rayleigh_out.assign(static_cast<std::size_t>(q.out_count) * kSource4dRayleighRank, 0.0f);
  }
  std::vector<double> rayleigh_in_sums(kSource4dRayleighRank, 0.0);
  for (int t = 0; t < kSource4dRayleighRank; ++t) {
    for (int ab = 0; ab < q.in_count; ++ab) rayleigh_in_sums[t] += rayleigh_in[static_cast<std::size_t>(t) * q.in_count + ab];
  }
  oneapi::tbb::parallel_for(0, q.out_count, [&](int cd) {
    const int c = cd / s.phi_size;
    const int d = cd % s.phi_size;
    const double theta_v = NodeAngle(c, s.mu_size, shared::kPi);
    const double phi_v = NodeAngle(d, s.phi_size, shared::kPi);
    const double cv = std::cos(theta_v);
    const double sv = std::sin(theta_v);
    const double cos_phi_v = std::cos(phi_v);
    const double sin_phi_v = std::sin(phi_v);
    std::vector<double> wr(q.in_count, 0.0);
    std::vector<double> wm(q.in_count, 0.0);
    double sum_r = 0.0;
    double sum_m = 0.0;
    for (const SubSample& sub : subs) {
      double pr = 0.0;
      double pm = 0.0;
      for (int mirror = 0; mirror < 2; ++mirror) {
        // cos(phi - phi_v) and cos(phi + phi_v), the view and its mirror image.
        const double cos_dphi = mirror == 0 ? sub.cos_phi * cos_phi_v + sub.sin_phi * sin_phi_v
                                            : sub.cos_phi * cos_phi_v - sub.sin_phi * sin_phi_v;
        const double nu = shared::ClampCosine(cv * sub.cos_theta + sv * sub.sin_theta * cos_dphi);
        pr += shared::GetRayleighPhase(atmosphere, nu);
        pm += shared::GetMiePhase(atmosphere, nu);
      }
      pr *= sub.solid_angle;
      pm *= sub.solid_angle;
      sum_r += pr;
      sum_m += pm;
      for (int k = 0; k < 4; ++k) {
        wr[sub.node[k]] += pr * sub.hat[k];
        wm[sub.node[k]] += pm * sub.hat[k];
      }
    }
    for (int ab = 0; ab < q.in_count; ++ab) {
      q.rayleigh[static_cast<std::size_t>(cd) * q.in_count + ab] = static_cast<float>(wr[ab] / sum_r);
      q.mie[static_cast<std::size_t>(cd) * q.in_count + ab] = static_cast<float>(wm[ab] / sum_m);
    }
    if (quadratic) {
      // p(nu_1) + p(nu_2) of the view and its mirror image = sum_t f_t(v) g_t(w): with
      // nu = X + Y +- Z (X = cv c, Y = sv s cos(phi) cos(phi_v), Z = sv s sin(phi) sin(phi_v)),
      // nu_1^2 + nu_2^2 = 2 (X + Y)^2 + 2 Z^2.
      const double f[kSource4dRayleighRank] = {2.0 * phase_a, 2.0 * phase_b * cv * cv,
                                               4.0 * phase_b * cv * sv * cos_phi_v,
                                               2.0 * phase_b * sv * sv * cos_phi_v * cos_phi_v,
                                               2.0 * phase_b * sv * sv * sin_phi_v * sin_phi_v};
      double norm = 0.0;
      for (int t = 0; t < kSource4dRayleighRank; ++t) norm += f[t] * rayleigh_in_sums[t];
      for (int t = 0; t < kSource4dRayleighRank; ++t) {
        q.rayleigh_out[static_cast<std::size_t>(cd) * kSource4dRayleighRank + t] = static_cast<float>(f[t] / norm);
      }
    }
  });
  return q;
}

namespace {

// One batch's orders: the running sums and the last two orders.
struct BatchOrders {
  std::vector<float> sum_r, sum_m, previous_r, g_r, g_m;
  // The sky's irradiance of the ground, orders >= 1 (the direct sun is added exactly where it is
  // used: its cos(theta_s) T would not interpolate well between sun-zenith rows).
  std::vector<glm::dvec3> irradiance_sum, previous_e, e;
  shared::Texture3D order_r, order_m;
  shared::Texture2D order_irradiance;
  GatherField field;
};

// The orders of every batch, on their transmittance tables (already in `tables`) and the
// quadrature, in step: each gathering pass marches the rays of all batches at once (the steps'
// points and the sun's coordinates are the same for all; GatherSingleRadiance,
// GatherMultipleRadiance), each batch's arithmetic as if alone.
void ComputeSource4dOrders(std::span<const shared::AtmosphereParameters> atmospheres, const Source4dSettings& s,
                           const Source4dQuadrature& q, std::span<Source4dTables* const> tables,
                           const std::function<void(std::string_view, double)>& record) {
  const auto note = [&](std::string_view pass, Clock::time_point start) {
    if (record) record(pass, MillisecondsSince(start));
  };
  const std::size_t batches = atmospheres.size();
  std::vector<Grid> grids;
  for (const shared::AtmosphereParameters& atmosphere : atmospheres) grids.push_back(Grid{atmosphere, s});
  const Grid& grid = grids.front();
  const int columns = grid.nodes() * 3;
  const std::size_t table_size = static_cast<std::size_t>(q.out_count) * columns;
  std::vector<BatchOrders> orders(batches);
  for (BatchOrders& o : orders) {
    o.sum_r.assign(table_size, 0.0f);
    o.sum_m.assign(table_size, 0.0f);
    o.irradiance_sum.assign(s.mu_s_size, glm::dvec3(0.0));
  }

  Clock::time_point start = Clock::now();
  if (s.orders >= 2) {
    std::vector<const shared::Texture2D*> transmittance;
    for (Source4dTables* t : tables) transmittance.push_back(&t->transmittance);
    std::vector<GatherField> fields = GatherSingleRadiance(grids, transmittance);
    for (std::size_t k = 0; k < batches; ++k) orders[k].field = std::move(fields[k]);
    note("source4d_gather_1", start);
  }
  for (int n = 2; n <= s.orders; ++n) {
    start = Clock::now();
    for (std::size_t k = 0; k < batches; ++k) {
      BatchOrders& o = orders[k];
      o.previous_r = std::move(o.g_r);
      Convolve(q, o.field, o.g_r, o.g_m);
      for (std::size_t i = 0; i < table_size; ++i) {
        o.sum_r[i] += o.g_r[i];
        o.sum_m[i] += o.g_m[i];
      }
      o.previous_e = std::move(o.e);
      o.e = GroundIrradiance(grids[k], q, o.field);
      for (int j = 0; j < s.mu_s_size; ++j) o.irradiance_sum[j] += o.e[j];
    }
    note("source4d_convolve_" + std::to_string(n), start);
    if (n == s.orders) break;
    start = Clock::now();
    std::vector<const shared::Texture3D*> rayleigh, mie;
    std::vector<const shared::Texture2D*> irradiance;
    for (std::size_t k = 0; k < batches; ++k) {
      BatchOrders& o = orders[k];
      WriteLogTable(grids[k], o.g_r, o.order_r);
      WriteLogTable(grids[k], o.g_m, o.order_m);
      o.order_irradiance = IrradianceTable(o.e);
      rayleigh.push_back(&o.order_r);
      mie.push_back(&o.order_m);
      irradiance.push_back(&o.order_irradiance);
    }
    std::vector<GatherField> fields = GatherMultipleRadiance(grids, rayleigh, mie, irradiance);
    for (std::size_t k = 0; k < batches; ++k) orders[k].field = std::move(fields[k]);
    note("source4d_gather_" + std::to_string(n), start);
  }

  start = Clock::now();
  for (std::size_t b = 0; b < batches; ++b) {
    BatchOrders& o = orders[b];
    if (s.tail && s.orders >= 3) {
      // Per node and channel, the ratio of the last two orders summed over directions.
      std::vector<double> last(columns, 0.0);
      std::vector<double> before(columns, 0.0);
      for (int cd = 0; cd < q.out_count; ++cd) {
        for (int k = 0; k < columns; ++k) {
          last[k] += o.g_r[static_cast<std::size_t>(cd) * columns + k];
          before[k] += o.previous_r[static_cast<std::size_t>(cd) * columns + k];
        }
      }
      std::vector<float> factor(columns, 0.0f);
      for (int k = 0; k < columns; ++k) {
        const double ratio = before[k] > 0.0 ? std::clamp(last[k] / before[k], 0.0, kSource4dMaxTailRatio) : 0.0;
        factor[k] = static_cast<float>(ratio / (1.0 - ratio));
      }
      for (int cd = 0; cd < q.out_count; ++cd) {
        for (int k = 0; k < columns; ++k) {
          const std::size_t i = static_cast<std::size_t>(cd) * columns + k;
          o.sum_r[i] += factor[k] * o.g_r[i];
          o.sum_m[i] += factor[k] * o.g_m[i];
        }
      }
      // The ground: E^(N-1) q / (1 - q) with q = E^(N-1) / E^(N-2).
      for (int j = 0; j < s.mu_s_size; ++j) {
        for (int c = 0; c < 3; ++c) {
          const double before_e = o.previous_e.empty() ? 0.0 : o.previous_e[j][c];
          const double ratio = before_e > 0.0 ? std::clamp(o.e[j][c] / before_e, 0.0, kSource4dMaxTailRatio) : 0.0;
          o.irradiance_sum[j][c] += o.e[j][c] * ratio / (1.0 - ratio);
        }
      }
    }
    WriteLogTable(grids[b], o.sum_r, tables[b]->rayleigh);
    WriteLogTable(grids[b], o.sum_m, tables[b]->mie);
    tables[b]->ground_irradiance = IrradianceTable(o.irradiance_sum);
  }
  note("source4d_sum", start);
}

}  // namespace

void ComputeSource4dTables(std::span<const shared::AtmosphereParameters> batches, const Source4dSettings& s,
                           std::span<Source4dTables* const> tables,
                           const std::function<void(std::string_view, double)>& record) {
  if (batches.empty() || batches.size() != tables.size()) {
    throw Error("ComputeSource4dTables needs one table set per batch and at least one batch");
  }
  const auto note = [&](std::string_view pass, Clock::time_point start) {
    if (record) record(pass, MillisecondsSince(start));
  };
  // The transmittance tables of all batches in one pass (the density integrals are shared).
  auto start = Clock::now();
  std::vector<shared::Texture2D*> transmittance;
  for (Source4dTables* t : tables) {
    t->mu_s_size = s.mu_s_size;
    t->transmittance = shared::Texture2D(s.transmittance_lut.x, s.transmittance_lut.y);
    transmittance.push_back(&t->transmittance);
  }
  ComputeTransmittanceTables(batches, s.transmittance_samples, transmittance);
  note("source4d_transmittance_lut", start);
  // The quadrature depends on the phase functions alone, which every batch of one atmosphere
  // shares (ToSharedParameters): computed once.
  start = Clock::now();
  const Source4dQuadrature q = ComputeSource4dQuadrature(batches.front(), s);
  note("source4d_quadrature", start);
  ComputeSource4dOrders(batches, s, q, tables, record);
}

void ComputeSource4dTables(const shared::AtmosphereParameters& atmosphere, const Source4dSettings& s,
                           Source4dTables& tables, const std::function<void(std::string_view, double)>& record) {
  Source4dTables* const one[] = {&tables};
  ComputeSource4dTables(std::span<const shared::AtmosphereParameters>(&atmosphere, 1), s, one, record);
}

}  // namespace atmo::cpu
