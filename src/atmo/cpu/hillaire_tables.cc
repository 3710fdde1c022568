#include "cpu/hillaire_tables.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

#if defined(__GLIBC__) && defined(__x86_64__)
// glibc's vector exp (libmvec): declaring the SIMD variants lets the compiler vectorise loops that
// call exp. glibc's own math.h does the same, but only under -ffast-math. This file is compiled
// with -fno-math-errno (src/atmo/CMakeLists.txt) so that exp has no side effect, and with
// -fopenmp-simd for the reductions (`omp simd` only; no OpenMP runtime).
extern "C" double exp(double) noexcept __attribute__((simd("notinbranch")));
#endif

namespace atmo::cpu {
namespace {

using shared::vec2;
using shared::vec3;

template <typename RowFunction>
void ForEachRow(int rows, const RowFunction& row_function) {
  oneapi::tbb::parallel_for(oneapi::tbb::blocked_range<int>(0, rows), [&](const oneapi::tbb::blocked_range<int>& range) {
    for (int y = range.begin(); y < range.end(); ++y) row_function(y);
  });
}

// A density layer prepared for branch-free evaluation: an absent exponential gets scale 0, so that
// exp never overflows into 0 * inf.
struct Layer {
  double exp_term, exp_scale, linear_term, constant_term;
};

Layer PrepareLayer(const shared::DensityProfileLayer& layer) {
  return {layer.exp_term, layer.exp_term == 0.0 ? 0.0 : layer.exp_scale, layer.linear_term, layer.constant_term};
}

// Writes layer(altitude_j) for j < n, before the clamp; an absent exponential costs nothing.
void EvaluateLayer(const Layer& layer, const double* altitude, int n, double* out) {
  if (layer.exp_term == 0.0) {
#pragma omp simd
    for (int j = 0; j < n; ++j) out[j] = layer.linear_term * altitude[j] + layer.constant_term;
  } else {
#pragma omp simd
    for (int j = 0; j < n; ++j) {
      const double h = altitude[j];
      out[j] = layer.exp_term * exp(layer.exp_scale * h) + layer.linear_term * h + layer.constant_term;
    }
  }
}

// Returns sum_j weight_j * density(altitude_j) for one profile, with the formula of
// shared::GetProfileDensity (altitudes are >= 0, so a lower layer of width 0 never applies). The
// layers are evaluated in loops without branches, which the compiler vectorises (a select or
// clamp there keeps it from using the vector exp); selection, clamp and sum follow.
double IntegrateProfile(const shared::DensityProfile& profile, const double* altitude, const double* weight, int n,
                        double* lower, double* upper) {
  const double width = profile.layers[0].width;
  EvaluateLayer(PrepareLayer(profile.layers[1]), altitude, n, upper);
  double sum = 0.0;
  if (width <= 0.0) {
#pragma omp simd reduction(+ : sum)
    for (int j = 0; j < n; ++j) sum += weight[j] * std::min(std::max(upper[j], 0.0), 1.0);
    return sum;
  }
  EvaluateLayer(PrepareLayer(profile.layers[0]), altitude, n, lower);
#pragma omp simd reduction(+ : sum)
  for (int j = 0; j < n; ++j) {
    const double d = altitude[j] < width ? lower[j] : upper[j];
    sum += weight[j] * std::min(std::max(d, 0.0), 1.0);
  }
  return sum;
}

// A table read at one fixed radius (a ray sample) for many sun angles: the texel rows and weight
// that the radius selects are found once; a lookup then blends four texels with them. The same
// bilinear GL_LINEAR rule as shared::texture.
class RowTaps {
 public:
  RowTaps() = default;
  RowTaps(const shared::Texture2D& table, double v) : table_(&table) {
    shared::detail::LinearTaps(v, table.height, false, y0_, y1_, wy_);
  }
  vec3 At(double u) const {
    int x0, x1;
    double wx;
    shared::detail::LinearTaps(u, table_->width, table_->repeat_u, x0, x1, wx);
    const vec3 a = glm::mix(vec3(table_->at(x0, y0_)), vec3(table_->at(x1, y0_)), wx);
    const vec3 b = glm::mix(vec3(table_->at(x0, y1_)), vec3(table_->at(x1, y1_)), wx);
    return glm::mix(a, b, wy_);
  }

 private:
  const shared::Texture2D* table_ = nullptr;
  int y0_ = 0, y1_ = 0;
  double wy_ = 0.0;
};

// shared::GetTransmittanceToSun at a fixed radius r: Bruneton's mapping split into its r part,
// computed once, and its mu_s part.
class TransmittanceToSunAtRadius {
 public:
  TransmittanceToSunAtRadius(const shared::AtmosphereParameters& a, const shared::Texture2D& table, double r)
      : a_(&a), r_(r) {
    const double H = std::sqrt((a.top_radius - a.bottom_radius) * (a.top_radius + a.bottom_radius));
    const double rho = shared::SafeSqrt((r - a.bottom_radius) * (r + a.bottom_radius));
    d_min_ = a.top_radius - r;
    d_max_ = rho + H;
    width_ = table.width;
    taps_ = RowTaps(table, shared::GetTextureCoordFromUnitRange(rho / H, table.height));
  }
  vec3 operator()(double mu_s) const {
    if (shared::RayIntersectsGround(*a_, r_, mu_s)) return vec3(0.0);
    const double d = shared::DistanceToTopAtmosphereBoundary(*a_, r_, mu_s);
    return taps_.At(shared::GetTextureCoordFromUnitRange((d - d_min_) / (d_max_ - d_min_), width_));
  }

 private:
  const shared::AtmosphereParameters* a_;
  double r_;
  double d_min_, d_max_;
  int width_;
  RowTaps taps_;
};

// shared::GetMultiScattering at a fixed radius r.
class MultipleScatteringAtRadius {
 public:
  MultipleScatteringAtRadius(const shared::AtmosphereParameters& a, const shared::Texture2D& table, double r)
      : width_(table.width) {
    const double x_r = std::clamp((r - a.bottom_radius) / (a.top_radius - a.bottom_radius), 0.0, 1.0);
    taps_ = RowTaps(table, shared::GetTextureCoordFromUnitRange(x_r, table.height));
  }
  vec3 operator()(double mu_s) const {
    return taps_.At(shared::GetTextureCoordFromUnitRange(std::clamp(0.5 * mu_s + 0.5, 0.0, 1.0), width_));
  }

 private:
  int width_;
  RowTaps taps_;
};

// The sun-independent part of one ray of the multiple-scattering integral.
struct MultipleScatteringRay {
  vec3 direction;
  double weight;  // how many directions of the set this one stands for (2 for a mirrored pair)
  std::vector<double> t;
  std::vector<double> r;
  std::vector<vec3> luminance_weight;  // throughput x step integral x scattering x isotropic phase
  std::vector<TransmittanceToSunAtRadius> sun_transmittance;
  bool hits_ground;
  double t_max;
  vec3 ground_throughput;
};

}  // namespace

void ComputeTransmittanceTable(const shared::AtmosphereParameters& a, int sample_count, shared::Texture2D& table) {
  const shared::ivec2 size(table.width, table.height);
  ForEachRow(size.y, [&](int y) {
    // The sample points and weights of shared::ComputeOpticalDepthOfSegment (one segment, or two
    // split at the lowest point of the ray), as altitudes and weights per unit length.
    std::vector<double> altitude(2 * sample_count + 2);
    std::vector<double> weight(2 * sample_count + 2);
    std::vector<double> lower(2 * sample_count + 2);
    std::vector<double> upper(2 * sample_count + 2);
    for (int x = 0; x < size.x; ++x) {
      double r, mu;
      shared::GetRMuFromTransmittanceTextureUv(a, size, vec2(x + 0.5, y + 0.5) / vec2(size), r, mu);
      const double d = shared::DistanceToTopAtmosphereBoundary(a, r, mu);
      int n = 0;
      auto add_segment = [&](double t_dense, double t_far, int intervals) {
        const double length = t_far - t_dense;
        const double scale = 2.0 * std::abs(length) / intervals;
        double* h = altitude.data() + n;
        double* w = weight.data() + n;
#pragma omp simd
        for (int i = 1; i <= intervals; ++i) {
          const double u = double(i) / intervals;
          const double t = t_dense + length * u * u;
          const double r_i = std::sqrt(std::max(t * t + 2.0 * r * mu * t + r * r, 0.0));
          h[i - 1] = std::max(r_i - a.bottom_radius, 0.0);
          w[i - 1] = scale * u;
        }
        w[intervals - 1] *= 0.5;  // the trapezoid's end point
        n += intervals;
      };
      if (mu >= 0.0 || sample_count < 2) {
        add_segment(0.0, d, sample_count);
      } else {
        const double t_lowest = std::min(-r * mu, d);
        const int n_before = std::max(sample_count / 2, 1);
        add_segment(t_lowest, 0.0, n_before);
        add_segment(t_lowest, d, std::max(sample_count - n_before, 1));
      }
      auto integrate = [&](const shared::DensityProfile& profile) {
        return IntegrateProfile(profile, altitude.data(), weight.data(), n, lower.data(), upper.data());
      };
      const vec3 integrals(integrate(a.rayleigh_density), integrate(a.mie_density), integrate(a.absorption_density));
      table.at(x, y) = glm::vec3(glm::exp(-shared::GetExtinctionFromDensities(a, integrals)));
    }
  });
}

void ComputeMultipleScatteringTable(const shared::AtmosphereParameters& a, const shared::Texture2D& transmittance,
                                    int direction_count, int sample_count, shared::Texture2D& table) {
  const shared::ivec2 size(table.width, table.height);
  // The directions of shared::GetMultiScatteringDirection; with the sun in the plane y = 0 the
  // direction (x, y, z) sees the same sun as (x, -y, z), so one of each mirrored pair is enough.
  std::vector<std::pair<vec3, double>> directions;
  if (direction_count == 2) {
    directions = {{shared::GetMultiScatteringDirection(0, 2), 1.0}, {shared::GetMultiScatteringDirection(1, 2), 1.0}};
  } else {
    // Directions count/2.. are the mirror images of 0..count/2-1.
    for (int k = 0; k < direction_count / 2; ++k) {
      directions.emplace_back(shared::GetMultiScatteringDirection(k, direction_count), 2.0);
    }
  }

  ForEachRow(size.y, [&](int y) {
    double r, unused_mu_s;
    shared::GetRMuSFromMultiScatteringTextureUv(a, size, vec2(0.5, y + 0.5) / vec2(size), r, unused_mu_s);
    std::vector<MultipleScatteringRay> rays;
    vec3 transfer_sum(0.0);
    for (const auto& [direction, weight] : directions) {
      MultipleScatteringRay ray;
      ray.direction = direction;
      ray.weight = weight;
      const double mu = direction.z;
      ray.hits_ground = shared::RayIntersectsGround(a, r, mu);
      ray.t_max = shared::DistanceToNearestAtmosphereBoundary(a, r, mu, ray.hits_ground);
      vec3 throughput(1.0);
      vec3 transfer(0.0);
      for (int i = 0; i < sample_count; ++i) {
        // Steps as in shared::IntegrateMultiScatteringRay.
        const double x_0 = double(i) / sample_count;
        const double x_1 = double(i + 1) / sample_count;
        const double dt = ray.t_max * (x_1 * x_1 - x_0 * x_0);
        const double t = 0.5 * ray.t_max * (x_0 * x_0 + x_1 * x_1);
        const double r_i = std::sqrt(t * t + 2.0 * r * mu * t + r * r);
        const shared::MediumSample medium = shared::SampleMedium(a, r_i);
        const vec3 step_transmittance = glm::exp(-medium.extinction * dt);
        const vec3 step_integral = throughput * shared::IntegrateStep(medium.extinction, step_transmittance, dt);
        ray.t.push_back(t);
        ray.r.push_back(r_i);
        ray.sun_transmittance.emplace_back(a, transmittance, r_i);
        ray.luminance_weight.push_back(step_integral * medium.scattering * shared::IsotropicPhaseFunction());
        transfer += step_integral * medium.scattering;
        throughput *= step_transmittance;
      }
      ray.ground_throughput = throughput;
      transfer_sum += transfer * weight;
      rays.push_back(std::move(ray));
    }
    const vec3 f_ms = transfer_sum / double(direction_count);

    for (int x = 0; x < size.x; ++x) {
      double unused_r, mu_s;
      shared::GetRMuSFromMultiScatteringTextureUv(a, size, vec2(x + 0.5, y + 0.5) / vec2(size), unused_r, mu_s);
      const vec3 sun(shared::SafeSqrt(1.0 - mu_s * mu_s), 0.0, mu_s);
      vec3 luminance_sum(0.0);
      for (const MultipleScatteringRay& ray : rays) {
        const double nu = glm::dot(ray.direction, sun);
        vec3 luminance(0.0);
        for (std::size_t i = 0; i < ray.t.size(); ++i) {
          const double mu_s_i = shared::ClampCosine((r * mu_s + ray.t[i] * nu) / ray.r[i]);
          luminance += ray.luminance_weight[i] * ray.sun_transmittance[i](mu_s_i);
        }
        if (ray.hits_ground) {
          const double r_g = a.bottom_radius;
          const double mu_s_g = shared::ClampCosine((r * mu_s + ray.t_max * nu) / r_g);
          luminance += ray.ground_throughput * shared::GetTransmittanceToSun(a, transmittance, r_g, mu_s_g) *
                       a.ground_albedo * (std::max(mu_s_g, 0.0) / shared::kPi);
        }
        luminance_sum += luminance * ray.weight;
      }
      const vec3 second_order = luminance_sum / double(direction_count);
      table.at(x, y) = glm::vec3(second_order / (vec3(1.0) - glm::min(f_ms, vec3(0.999))));
    }
  });
}

void ComputeSkyViewTable(const shared::AtmosphereParameters& a, const shared::Texture2D& transmittance,
                         const shared::Texture2D& multiple_scattering, double r, double mu_s, int sample_count,
                         shared::Texture2D& table) {
  const shared::ivec2 size(table.width, table.height);
  ForEachRow(size.y, [&](int y) {
    // The view zenith of the row; the columns only change the azimuth from the sun.
    double mu, unused_azimuth;
    shared::GetViewAnglesFromSkyViewTextureUv(a, size, r, vec2(0.5, y + 0.5) / vec2(size), mu, unused_azimuth);
    const bool hits_ground = shared::RayIntersectsGround(a, r, mu);
    const double t_max = shared::DistanceToNearestAtmosphereBoundary(a, r, mu, hits_ground);
    // Steps as in shared::IntegrateScatteredRadiance.
    std::vector<double> t(sample_count), r_i(sample_count);
    std::vector<vec3> weight(sample_count), rayleigh(sample_count), mie(sample_count), scattering(sample_count);
    std::vector<TransmittanceToSunAtRadius> sun_transmittance;
    std::vector<MultipleScatteringAtRadius> multiple_scattering_at;
    vec3 throughput(1.0);
    for (int i = 0; i < sample_count; ++i) {
      const double x_0 = double(i) / sample_count;
      const double x_1 = double(i + 1) / sample_count;
      const double t_0 = t_max * x_0 * x_0;
      const double t_1 = t_max * x_1 * x_1;
      const double dt = t_1 - t_0;
      t[i] = 0.5 * (t_0 + t_1);
      r_i[i] = std::sqrt(t[i] * t[i] + 2.0 * r * mu * t[i] + r * r);
      sun_transmittance.emplace_back(a, transmittance, r_i[i]);
      multiple_scattering_at.emplace_back(a, multiple_scattering, r_i[i]);
      const shared::MediumSample medium = shared::SampleMedium(a, r_i[i]);
      const vec3 step_transmittance = glm::exp(-medium.extinction * dt);
      weight[i] = throughput * shared::IntegrateStep(medium.extinction, step_transmittance, dt);
      rayleigh[i] = medium.rayleigh_scattering;
      mie[i] = medium.mie_scattering;
      scattering[i] = medium.scattering;
      throughput *= step_transmittance;
    }
    // Column x and column (width - x) see azimuths phi and 2 pi - phi: the same nu.
    for (int x = 0; 2 * x <= size.x; ++x) {
      double unused_mu, azimuth;
      shared::GetViewAnglesFromSkyViewTextureUv(a, size, r, vec2(x + 0.5, y + 0.5) / vec2(size), unused_mu, azimuth);
      const double nu = shared::SafeSqrt(1.0 - mu * mu) * shared::SafeSqrt(1.0 - mu_s * mu_s) * std::cos(azimuth) +
                        mu * mu_s;
      const double rayleigh_phase = shared::GetRayleighPhase(a, nu);
      const double mie_phase = shared::GetMiePhase(a, nu);
      vec3 radiance(0.0);
      for (int i = 0; i < sample_count; ++i) {
        const double mu_s_i = shared::ClampCosine((r * mu_s + t[i] * nu) / r_i[i]);
        const vec3 source = sun_transmittance[i](mu_s_i) * (rayleigh[i] * rayleigh_phase + mie[i] * mie_phase) +
                            multiple_scattering_at[i](mu_s_i) * scattering[i];
        radiance += weight[i] * source;
      }
      table.at(x, y) = glm::vec3(radiance);
      table.at((size.x - x) % size.x, y) = glm::vec3(radiance);
    }
  });
}

}  // namespace atmo::cpu
