#include "cpu/hillaire_tables.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

#include "atmo/memory.h"
#include "cpu/vector_math.h"

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
using shared::vec4;

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

// Writes density(altitude_j) for j < n, for one profile, with the formula of
// shared::GetProfileDensity (altitudes are >= 0, so a lower layer of width 0 never applies). The
// layers are evaluated in loops without branches, which the compiler vectorises (a select or
// clamp there keeps it from using the vector exp); selection and clamp follow.
void ProfileDensities(const shared::DensityProfile& profile, const double* altitude, int n, double* lower,
                      double* __restrict density) {
  const double width = profile.layers[0].width;
  EvaluateLayer(PrepareLayer(profile.layers[1]), altitude, n, density);
  if (width <= 0.0) {
#pragma omp simd
    for (int j = 0; j < n; ++j) density[j] = std::min(std::max(density[j], 0.0), 1.0);
    return;
  }
  EvaluateLayer(PrepareLayer(profile.layers[0]), altitude, n, lower);
#pragma omp simd
  for (int j = 0; j < n; ++j) {
    const double d = altitude[j] < width ? lower[j] : density[j];
    density[j] = std::min(std::max(d, 0.0), 1.0);
  }
}

// sum_j weight_j value_j for j < n.
double WeightedSum(const double* __restrict weight, const double* __restrict value, int n) {
  double sum = 0.0;
#pragma omp simd reduction(+ : sum)
  for (int j = 0; j < n; ++j) sum += weight[j] * value[j];
  return sum;
}

// sum_j weight_j density_j for j < n, per medium: density holds four media per altitude.
vec4 WeightedSums(const double* __restrict weight, const float* __restrict density, int n) {
  double sum[4] = {};
  for (int j = 0; j < n; ++j) {
    for (int m = 0; m < 4; ++m) sum[m] += weight[j] * density[4 * j + m];
  }
  return vec4(sum[0], sum[1], sum[2], sum[3]);
}

// shared::GetTabulatedDensities for many altitudes, in passes the compiler vectorises: the knot
// index and fraction, the four media's log densities, a float exp; then the linear interpolation
// of the intervals next to a knot of density 0 (which intervals, and the knots' densities,
// precomputed). A medium absent from the table (no water vapour) gets 0.
class TabulatedDensities {
 public:
  explicit TabulatedDensities(const shared::AtmosphereParameters& a) : a_(a) {
    const double zero = shared::kDensityTableLogZero + 1.0;
    for (int i = 0; i + 1 < shared::kDensityTableSize; ++i) {
      for (int m = 0; m < 4; ++m) {
        linear_[m][i] = std::min(a.density_table[i][m], a.density_table[i + 1][m]) < zero;
        any_linear_[m] = any_linear_[m] || linear_[m][i];
      }
    }
    for (int i = 0; i < shared::kDensityTableSize; ++i) {
      for (int m = 0; m < 4; ++m) {
        present_[m] = present_[m] || a.density_table[i][m] > shared::kDensityTableLogZero;
        knot_density_[m][i] = std::exp(a.density_table[i][m]);
      }
    }
  }

  // The knot interval (index) and the fraction within it of each of n altitudes, for Densities.
  void Locate(const double* altitude, int n, std::vector<double>& fraction, std::vector<int>& index) const {
    constexpr int kLast = shared::kDensityTableSize - 1;
    fraction.resize(n);
    index.resize(n);
    const double inverse_top = 1.0 / a_.density_table_top;
    const double knot_scale = a_.density_table_top / double(kLast * kLast);
    double* __restrict f = fraction.data();
#pragma omp simd
    for (int j = 0; j < n; ++j) {
      const double u = std::sqrt(std::min(std::max(altitude[j] * inverse_top, 0.0), 1.0)) * kLast;
      const double lower = std::min(std::floor(u), double(kLast - 1));
      const double h_0 = knot_scale * lower * lower;
      const double h_1 = knot_scale * (lower + 1.0) * (lower + 1.0);
      f[j] = std::min(std::max((altitude[j] - h_0) / (h_1 - h_0), 0.0), 1.0);
      index[j] = static_cast<int>(lower);
    }
  }

  // Writes the four media's densities at the n altitudes that Locate placed into
  // density[4 j + m], m the medium; 0 for a medium absent from the table. The knots' logarithms
  // are interpolated in double, the four media of a sample at once, and their exp taken in float
  // (ExpFloat, which vectorises on every target): its error, a few 1e-7, is far below the table's
  // own approximation of a profile (DensityTable tests: 2e-4).
  void Densities(const std::vector<double>& fraction, const std::vector<int>& index, int n,
                 std::vector<float>& density) const {
    density.resize(4 * static_cast<std::size_t>(n));
    float* __restrict d = density.data();
    for (int j = 0; j < n; ++j) {
      const shared::vec4& l_0 = a_.density_table[index[j]];
      const shared::vec4& l_1 = a_.density_table[index[j] + 1];
      const double f = fraction[j];
      for (int m = 0; m < 4; ++m) d[4 * j + m] = static_cast<float>(l_0[m] + (l_1[m] - l_0[m]) * f);
    }
#pragma omp simd
    for (int k = 0; k < 4 * n; ++k) d[k] = ExpFloat(d[k]);
    for (int m = 0; m < 4; ++m) {
      if (!present_[m]) {
        for (int j = 0; j < n; ++j) d[4 * j + m] = 0.0f;
      } else if (any_linear_[m]) {
        const double* knots = knot_density_[m];
        for (int j = 0; j < n; ++j) {
          if (!linear_[m][index[j]]) continue;
          const double d_0 = knots[index[j]];
          d[4 * j + m] = static_cast<float>(d_0 + (knots[index[j] + 1] - d_0) * fraction[j]);
        }
      }
    }
  }

 private:
  const shared::AtmosphereParameters& a_;
  bool linear_[4][shared::kDensityTableSize] = {};
  bool any_linear_[4] = {};
  bool present_[4] = {};  // some knot above kDensityTableLogZero (water vapour may have none)
  double knot_density_[4][shared::kDensityTableSize] = {};  // exp of the table's knots, per medium
};

// For the samples (t_i, r_i) of a ray and a sun with r mu_s = r_mu_s, nu = cos(ray, sun): whether
// the sun is above each sample's horizon (lit, 1 or 0), and the texel columns of the
// transmittance (Bruneton's x_mu) and multiple-scattering (mu_s) tables. Kept out of line, on
// plain arrays, so that the compiler vectorises it wherever it is called from.
__attribute__((noinline)) void SunColumns(int n, double r_mu_s, double nu, const double* __restrict t,
                                          const double* __restrict r, const double* __restrict inverse_r,
                                          const double* __restrict c_ground, const double* __restrict c_top,
                                          const double* __restrict d_min, const double* __restrict inverse_range,
                                          double t_columns, double m_columns, double* __restrict lit,
                                          double* __restrict sun_column, double* __restrict ms_column) {
#pragma omp simd
  for (int i = 0; i < n; ++i) {
    const double r_i = r[i];
    // The clamps map NaN into the table (shared::ClampToRange): these columns become indices.
    const double mu = shared::ClampToRange((r_mu_s + t[i] * nu) * inverse_r[i], -1.0, 1.0);
    const double r2_mu2 = r_i * r_i * mu * mu;
    lit[i] = (mu < 0.0 && c_ground[i] + r2_mu2 >= 0.0) ? 0.0 : 1.0;
    const double root = std::sqrt(std::max(c_top[i] + r2_mu2, 0.0));
    const double d = mu > 0.0 ? c_top[i] / (r_i * mu + root) : -r_i * mu + root;
    sun_column[i] = shared::ClampToRange((std::max(d, 0.0) - d_min[i]) * inverse_range[i], 0.0, 1.0) * t_columns;
    ms_column[i] = shared::GetMultiScatteringUnitFromMuS(mu) * m_columns;
  }
}

// SunColumns' multiple-scattering columns alone, for lookups of that table without the sun's
// transmittance.
__attribute__((noinline)) void MultipleScatteringColumns(int n, double r_mu_s, double nu, const double* __restrict t,
                                                         const double* __restrict inverse_r, double m_columns,
                                                         double* __restrict ms_column) {
#pragma omp simd
  for (int i = 0; i < n; ++i) {
    const double mu = shared::ClampToRange((r_mu_s + t[i] * nu) * inverse_r[i], -1.0, 1.0);
    ms_column[i] = shared::GetMultiScatteringUnitFromMuS(mu) * m_columns;
  }
}

// shared::DecodeMultiScattering over `count` floats (the components of an array of texels), in
// float like the table (ExpFloat, which the compiler vectorises on every target).
__attribute__((noinline)) void DecodeMultipleScattering(int count, float* __restrict values) {
#pragma omp simd
  for (int k = 0; k < count; ++k) {
    const float psi = ExpFloat(values[k]);
    values[k] = psi < 2e-30f ? 0.0f : psi;
  }
}

// A float table padded to four components, so that a texel is one 16-byte load.
struct PaddedTable {
  explicit PaddedTable(const shared::Texture2D& table) : width(table.width), height(table.height) {
    texels.reserve(table.texels.size());
    for (const glm::vec3& t : table.texels) texels.emplace_back(t, 0.0f);
  }
  int width;
  int height;
  std::vector<glm::vec4> texels;
};

// The transmittance-to-sun and multiple-scattering lookups at the samples of one ray, for many
// suns (the columns of a table row). What depends only on a sample's radius is computed once:
// the texel rows and weight of both tables and the constants of Bruneton's mapping. Per sun, a
// loop without branches (vectorised) finds each sample's sun cosine, planet shadow and texel
// column, and a second loop blends the texels. The formulas are those of
// shared::GetTransmittanceToSun and shared::GetMultiScattering (tested texel by texel).
class SunLookupsAlongRay {
 public:
  SunLookupsAlongRay(const shared::AtmosphereParameters& a, const PaddedTable& transmittance,
                     const PaddedTable* multiple_scattering, double r, int sample_count)
      : a_(a), transmittance_(transmittance), multiple_scattering_(multiple_scattering), r_(r) {
    for (std::vector<double>* v : {&t_, &r_i_, &inverse_r_, &c_ground_, &c_top_, &d_min_, &inverse_range_}) {
      v->reserve(sample_count);
    }
    transmittance_rows_.reserve(sample_count);
    multiple_scattering_rows_.reserve(sample_count);
    sun_column_.resize(sample_count);
    multiple_scattering_column_.resize(sample_count);
    lit_.resize(sample_count);
  }

  void AddSample(double t, double r_i) {
    const double H = std::sqrt((a_.top_radius - a_.bottom_radius) * (a_.top_radius + a_.bottom_radius));
    const double rho = shared::SafeSqrt((r_i - a_.bottom_radius) * (r_i + a_.bottom_radius));
    t_.push_back(t);
    r_i_.push_back(r_i);
    inverse_r_.push_back(1.0 / r_i);
    c_ground_.push_back((a_.bottom_radius - r_i) * (a_.bottom_radius + r_i));
    c_top_.push_back((a_.top_radius - r_i) * (a_.top_radius + r_i));
    d_min_.push_back(a_.top_radius - r_i);
    inverse_range_.push_back(1.0 / (rho + H - (a_.top_radius - r_i)));
    AddRow(transmittance_, shared::GetTextureCoordFromUnitRange(rho / H, transmittance_.height), transmittance_rows_);
    if (multiple_scattering_ != nullptr) {
      const double x_r = shared::ClampToRange((r_i - a_.bottom_radius) / (a_.top_radius - a_.bottom_radius), 0.0, 1.0);
      AddRow(*multiple_scattering_, shared::GetTextureCoordFromUnitRange(x_r, multiple_scattering_->height),
             multiple_scattering_rows_);
    }
    if (sun_column_.size() < t_.size()) {
      sun_column_.resize(t_.size());
      multiple_scattering_column_.resize(t_.size());
      lit_.resize(t_.size());
    }
  }

  std::size_t size() const { return t_.size(); }
  double t(std::size_t i) const { return t_[i]; }
  double r(std::size_t i) const { return r_i_[i]; }

  // For the gathered orders: sum_i weights[i] * (the multiple-scattering table at sample i) for the
  // sun at zenith cosine mu_s and nu = cos(ray direction, sun), in float (weights' w is 0).
  glm::vec4 SumMultipleScattering(double mu_s, double nu, const glm::vec4* weights) const {
    const int n = static_cast<int>(t_.size());
    MultipleScatteringColumns(n, r_ * mu_s, nu, t_.data(), inverse_r_.data(), multiple_scattering_->width - 1,
                              multiple_scattering_column_.data());
    BlendMultipleScattering(n);
    glm::vec4 sum(0.0f);
    for (int i = 0; i < n; ++i) sum += blended_[i] * weights[i];
    return sum;
  }

  // For the sun at zenith cosine mu_s and nu = cos(ray direction, sun): the sum over the samples
  // of T_i (rayleigh[i] rayleigh_phase + mie[i] mie_phase) [+ Psi_i scattering[i]], T_i the
  // transmittance to the sun (0 in the planet's shadow) and Psi_i the multiple-scattering table
  // there, in float like the tables (the weights' w is 0). Without `scattering` (null) the
  // multiple-scattering table is not read. Not thread-safe (scratch arrays); one instance per thread.
  glm::vec4 SumSunlight(double mu_s, double nu, const glm::vec4* rayleigh, float rayleigh_phase, const glm::vec4* mie,
                        float mie_phase, const glm::vec4* scattering) const {
    const int n = static_cast<int>(t_.size());
    const double t_columns = transmittance_.width - 1;
    const double m_columns = multiple_scattering_ != nullptr ? multiple_scattering_->width - 1 : 0.0;
    SunColumns(n, r_ * mu_s, nu, t_.data(), r_i_.data(), inverse_r_.data(), c_ground_.data(), c_top_.data(),
               d_min_.data(), inverse_range_.data(), t_columns, m_columns, lit_.data(), sun_column_.data(),
               multiple_scattering_column_.data());
    glm::vec4 sum(0.0f);
    for (int i = 0; i < n; ++i) {
      const glm::vec4 sun = Blend(transmittance_, transmittance_rows_[i], sun_column_[i]) * static_cast<float>(lit_[i]);
      sum += sun * (rayleigh[i] * rayleigh_phase + mie[i] * mie_phase);
    }
    if (scattering != nullptr) {
      BlendMultipleScattering(n);
      for (int i = 0; i < n; ++i) sum += blended_[i] * scattering[i];
    }
    return sum;
  }

 private:
  struct Row {
    const glm::vec4* texels0;  // the two texel rows GL_LINEAR blends, and the second one's weight
    const glm::vec4* texels1;
    float wy;
  };

  static void AddRow(const PaddedTable& table, double v, std::vector<Row>& rows) {
    Row row;
    int y0, y1;
    double wy;
    shared::detail::LinearTaps(v, table.height, false, y0, y1, wy);
    row.texels0 = &table.texels[static_cast<std::size_t>(y0) * table.width];
    row.texels1 = &table.texels[static_cast<std::size_t>(y1) * table.width];
    row.wy = static_cast<float>(wy);
    rows.push_back(row);
  }

  // The multiple-scattering table at the first n samples (their columns already found), blended
  // and decoded in float like the table itself, into blended_ (the padding lane holds 1).
  void BlendMultipleScattering(int n) const {
    blended_.resize(n);
    for (int i = 0; i < n; ++i) {
      blended_[i] = Blend(*multiple_scattering_, multiple_scattering_rows_[i], multiple_scattering_column_[i]);
    }
    static_assert(sizeof(glm::vec4) == 4 * sizeof(float), "vec4 arrays are packed floats");
    DecodeMultipleScattering(4 * n, &blended_[0].x);
  }

  // GL_LINEAR at texel coordinate s (texel centres at integers, s in [0, width - 1]) of `row`, in
  // float like the table itself.
  static glm::vec4 Blend(const PaddedTable& table, const Row& row, double s) {
    // s is in [0, width - 1] (its callers clamp it, NaN included); the guard keeps the cast defined.
    const int x0 = s > 0.0 ? static_cast<int>(std::min(s, static_cast<double>(table.width - 1))) : 0;
    const int x1 = std::min(x0 + 1, table.width - 1);
    const float wx = static_cast<float>(s - x0);
    const glm::vec4 a = row.texels0[x0] + (row.texels0[x1] - row.texels0[x0]) * wx;
    const glm::vec4 b = row.texels1[x0] + (row.texels1[x1] - row.texels1[x0]) * wx;
    return a + (b - a) * row.wy;
  }

  const shared::AtmosphereParameters& a_;
  const PaddedTable& transmittance_;
  const PaddedTable* multiple_scattering_;
  double r_;
  std::vector<double> t_, r_i_, inverse_r_, c_ground_, c_top_, d_min_, inverse_range_;
  std::vector<Row> transmittance_rows_, multiple_scattering_rows_;
  mutable std::vector<double> sun_column_, multiple_scattering_column_, lit_;
  mutable std::vector<glm::vec4> blended_;
};

// The sun-independent part of one ray of the multiple-scattering integral.
struct MultipleScatteringRay {
  vec3 direction;
  double weight;  // how many directions of the set this one stands for (2 for a mirrored pair)
  SunLookupsAlongRay samples;
  // In float, w = 0:
  std::vector<glm::vec4> rayleigh_weight;  // throughput x step integral x Rayleigh scattering
  std::vector<glm::vec4> mie_weight;       // throughput x step integral x Mie scattering
  std::vector<glm::vec4> scattering_weight;  // their sum (the gathered orders' isotropic phase)
  bool hits_ground;
  double t_max;
  vec3 ground_throughput;
};

// The sun-independent part of shared::IntegrateScatteredRadianceInside along one ray (an observer
// at radius r, zenith cosine mu, the ray t_max long): its samples' lookups and, per sample, the
// step weight (throughput x step integral) times each medium's scattering, in float (w = 0).
class ScatteringRay {
 public:
  ScatteringRay(const shared::AtmosphereParameters& a, const PaddedTable& transmittance,
                const PaddedTable& multiple_scattering, double r, double mu, double t_max, int sample_count)
      : samples_(a, transmittance, &multiple_scattering, r, sample_count) {
    rayleigh_.reserve(sample_count);
    mie_.reserve(sample_count);
    scattering_.reserve(sample_count);
    vec3 throughput(1.0);
    for (int i = 0; i < sample_count; ++i) {
      // Steps as in shared::IntegrateScatteredRadianceInside.
      const double x_0 = double(i) / sample_count;
      const double x_1 = double(i + 1) / sample_count;
      const double t_0 = t_max * x_0 * x_0;
      const double t_1 = t_max * x_1 * x_1;
      const double dt = t_1 - t_0;
      const double t = 0.5 * (t_0 + t_1);
      const double r_i = std::sqrt(t * t + 2.0 * r * mu * t + r * r);
      samples_.AddSample(t, r_i);
      const shared::MediumSample medium = shared::SampleMedium(a, r_i);
      const vec3 step_transmittance = glm::exp(-medium.extinction * dt);
      const vec3 weight = throughput * shared::IntegrateStep(medium.extinction, step_transmittance, dt);
      rayleigh_.emplace_back(glm::vec3(weight * medium.rayleigh_scattering), 0.0f);
      mie_.emplace_back(glm::vec3(weight * medium.mie_scattering), 0.0f);
      scattering_.emplace_back(glm::vec3(weight * medium.scattering), 0.0f);
      throughput *= step_transmittance;
    }
  }

  // The radiance scattered towards the observer for a sun at zenith cosine mu_s, nu = cos(ray
  // direction, sun). Not thread-safe (SunLookupsAlongRay's scratch arrays).
  glm::vec4 Radiance(const shared::AtmosphereParameters& a, double mu_s, double nu) const {
    return samples_.SumSunlight(mu_s, nu, rayleigh_.data(), static_cast<float>(shared::GetRayleighPhase(a, nu)),
                                mie_.data(), static_cast<float>(shared::GetMiePhase(a, nu)), scattering_.data());
  }

 private:
  SunLookupsAlongRay samples_;
  std::vector<glm::vec4> rayleigh_, mie_, scattering_;
};

}  // namespace

void ComputeTransmittanceTable(const shared::AtmosphereParameters& a, int sample_count, shared::Texture2D& table) {
  shared::Texture2D* tables[] = {&table};
  ComputeTransmittanceTables(std::span<const shared::AtmosphereParameters>(&a, 1), sample_count, tables);
}

void ComputeTransmittanceTables(std::span<const shared::AtmosphereParameters> batches, int sample_count,
                                std::span<shared::Texture2D* const> tables) {
  const shared::AtmosphereParameters& a = batches.front();  // the geometry and profiles of all
  const shared::ivec2 size(tables.front()->width, tables.front()->height);
  const TabulatedDensities tabulated(a);
  const int n = sample_count + 1;  // samples per texel
  // The samples of a block of texels in one array (texel k's at [k n, (k + 1) n)), so that each
  // density profile runs in one long vectorised loop per block rather than a short one per texel;
  // a block of 16 texels of 41 samples keeps the arrays in the core's caches.
  constexpr int kBlockTexels = 16;
  ForEachRow(size.y, [&](int y) {
    const int block_samples = std::min(kBlockTexels, size.x) * n;
    std::vector<double> altitude(block_samples), weight(block_samples), lower(block_samples), density(block_samples);
    std::vector<double> fraction;
    std::vector<int> index;
    std::vector<float> densities;
    std::vector<vec4> integrals(kBlockTexels);
    for (int x_0 = 0; x_0 < size.x; x_0 += kBlockTexels) {
      const int texels = std::min(kBlockTexels, size.x - x_0);
      const int count = texels * n;
      for (int k = 0; k < texels; ++k) {
        double r, mu;
        shared::GetRMuFromTransmittanceTextureUv(a, size, vec2(x_0 + k + 0.5, y + 0.5) / vec2(size), r, mu);
        const double d = shared::DistanceToTopAtmosphereBoundary(a, r, mu);
        // The sample points and weights of shared::ComputeOpticalDepthToTopAtmosphereBoundary.
        const double t_low = std::clamp(-r * mu, 0.0, d);
        const double s_0 = -std::sqrt(t_low);
        const double ds = (std::sqrt(d - t_low) - s_0) / sample_count;
        double* __restrict h = altitude.data() + static_cast<std::size_t>(k) * n;
        double* __restrict w = weight.data() + static_cast<std::size_t>(k) * n;
#pragma omp simd
        for (int i = 0; i < n; ++i) {
          const double s = s_0 + i * ds;
          const double t = t_low + s * std::abs(s);
          const double r_i = std::sqrt(std::max(t * t + 2.0 * r * mu * t + r * r, 0.0));
          h[i] = std::max(r_i - a.bottom_radius, 0.0);
          w[i] = 2.0 * std::abs(s) * ds;
        }
        w[0] *= 0.5;
        w[sample_count] *= 0.5;
      }
      // The density integrals of each texel, which do not depend on the channels: once for every batch.
      std::fill(integrals.begin(), integrals.end(), vec4(0.0));
      const auto integrate = [&](int m) {
        for (int k = 0; k < texels; ++k) {
          const std::size_t first = static_cast<std::size_t>(k) * n;
          integrals[k][m] = WeightedSum(weight.data() + first, density.data() + first, n);
        }
      };
      if (a.density_table_enabled) {
        tabulated.Locate(altitude.data(), count, fraction, index);
        tabulated.Densities(fraction, index, count, densities);
        for (int k = 0; k < texels; ++k) {
          const std::size_t first = static_cast<std::size_t>(k) * n;
          integrals[k] = WeightedSums(weight.data() + first, densities.data() + 4 * first, n);
        }
      } else {
        const shared::DensityProfile* profiles[] = {&a.rayleigh_density, &a.mie_density, &a.absorption_density};
        for (int m = 0; m < 3; ++m) {
          ProfileDensities(*profiles[m], altitude.data(), count, lower.data(), density.data());
          integrate(m);
        }
      }
      for (int k = 0; k < texels; ++k) {
        for (std::size_t b = 0; b < batches.size(); ++b) {
          tables[b]->at(x_0 + k, y) = glm::vec3(glm::exp(-shared::GetExtinctionFromDensities(batches[b], integrals[k])));
        }
      }
    }
  });
}

void ComputeMultipleScatteringTable(const shared::AtmosphereParameters& a, const shared::Texture2D& transmittance,
                                    int direction_count, int sample_count, bool media_phase,
                                    const glm::dvec3& ground_transfer, shared::Texture2D& table, int gathered_orders,
                                    int gather_direction_count) {
  const shared::ivec2 size(table.width, table.height);
  if (gather_direction_count <= 0) gather_direction_count = direction_count;
  if (gathered_orders > 1) {
    // The gathered orders pass over every row again: the rays of all rows are kept (about 200
    // bytes per step, from the ray's arrays), once per direction set, and a float copy of the table.
    const auto marched = [](int count) { return count == 2 ? 2.0 : count / 2.0; };
    const double rays_per_row =
        marched(direction_count) + (gather_direction_count != direction_count ? marched(gather_direction_count) : 0.0);
    CheckMemory("hillaire's gathered multiple-scattering orders (" + std::to_string(size.x) + "x" +
                    std::to_string(size.y) + " texels, " + std::to_string(sample_count) + " samples per ray)",
                200.0 * size.y * rays_per_row * sample_count + 16.0 * size.x * size.y);
  }
  const PaddedTable padded_transmittance(transmittance);
  // With gathered orders, the previous order's mean radiance, looked up along the rays like the
  // finished table (log texels, GL_LINEAR); its texels are rewritten in place for each order.
  PaddedTable previous_order(table);
  const PaddedTable* lookup = gathered_orders > 1 ? &previous_order : nullptr;

  // The directions of shared::GetMultiScatteringDirection, with the weight each stands for; with
  // the sun in the plane y = 0 the direction (x, y, z) sees the same sun as (x, -y, z), so one of
  // each mirrored pair is enough.
  const auto directions_of = [](int count) {
    std::vector<std::pair<vec3, double>> directions;
    if (count == 2) {
      directions = {{shared::GetMultiScatteringDirection(0, 2), 1.0}, {shared::GetMultiScatteringDirection(1, 2), 1.0}};
    } else {
      // Directions count/2.. are the mirror images of 0..count/2-1.
      for (int k = 0; k < count / 2; ++k) directions.emplace_back(shared::GetMultiScatteringDirection(k, count), 2.0);
    }
    return directions;
  };
  // The sun-independent part of the rays from row y's point into `rays`; returns the row's f_ms.
  const auto build_row = [&](int y, const std::vector<std::pair<vec3, double>>& directions, int count,
                             std::vector<MultipleScatteringRay>& rays) {
    double r, unused_mu_s;
    shared::GetRMuSFromMultiScatteringTextureUv(a, size, vec2(0.5, y + 0.5) / vec2(size), r, unused_mu_s);
    rays.reserve(directions.size());
    vec3 transfer_sum(0.0);
    for (const auto& [direction, weight] : directions) {
      MultipleScatteringRay ray{direction, weight, SunLookupsAlongRay(a, padded_transmittance, lookup, r, sample_count),
                                {}, {}, {}, false, 0.0, vec3(0.0)};
      ray.rayleigh_weight.reserve(sample_count);
      ray.mie_weight.reserve(sample_count);
      ray.scattering_weight.reserve(sample_count);
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
        ray.samples.AddSample(t, r_i);
        const vec3 rayleigh_weight = step_integral * medium.rayleigh_scattering;
        const vec3 mie_weight = step_integral * medium.mie_scattering;
        ray.rayleigh_weight.emplace_back(glm::vec3(rayleigh_weight), 0.0f);
        ray.mie_weight.emplace_back(glm::vec3(mie_weight), 0.0f);
        ray.scattering_weight.emplace_back(glm::vec3(rayleigh_weight + mie_weight), 0.0f);
        transfer += step_integral * medium.scattering;
        throughput *= step_transmittance;
      }
      ray.ground_throughput = throughput;
      if (ray.hits_ground) transfer += throughput * a.ground_albedo * ground_transfer;
      transfer_sum += transfer * weight;
      rays.push_back(std::move(ray));
    }
    return transfer_sum / double(count);
  };

  // Psi_n, the mean over the sphere of order n's light, at every texel (shared::
  // ComputeMultiScatteringFirstOrderTexel for n = 1, shared::ComputeMultiScatteringGatherTexel for
  // n > 1), and E_n on the ground row (row 0: r = bottom radius) for order n + 1.
  const std::size_t texel_count = static_cast<std::size_t>(size.x) * size.y;
  std::vector<vec3> order(texel_count), next(texel_count), sum, f_ms(size.y);
  shared::Texture2D ground_irradiance(size.x, 1);
  std::vector<vec3> next_ground_irradiance(size.x);
  // Order n of row y from its rays (`count` directions) into `next`.
  const auto gather_row = [&](int n, int y, const std::vector<MultipleScatteringRay>& rays, int count) {
    double r, unused_mu_s;
    shared::GetRMuSFromMultiScatteringTextureUv(a, size, vec2(0.5, y + 0.5) / vec2(size), r, unused_mu_s);
    for (int x = 0; x < size.x; ++x) {
      double unused_r, mu_s;
      shared::GetRMuSFromMultiScatteringTextureUv(a, size, vec2(x + 0.5, y + 0.5) / vec2(size), unused_r, mu_s);
      const vec3 sun(shared::SafeSqrt(1.0 - mu_s * mu_s), 0.0, mu_s);
      vec3 luminance_sum(0.0), irradiance_sum(0.0);
      for (const MultipleScatteringRay& ray : rays) {
        const double nu = glm::dot(ray.direction, sun);
        vec3 luminance(0.0);
        const double mu_s_g = ray.hits_ground ? shared::ClampCosine((r * mu_s + ray.t_max * nu) / a.bottom_radius) : 0.0;
        if (n == 1) {
          // The first scattering's phase, constant along the ray (as in shared::IntegrateMultiScatteringRay).
          const double rayleigh_phase = media_phase ? shared::GetRayleighPhase(a, nu) : shared::IsotropicPhaseFunction();
          const double mie_phase = media_phase ? shared::GetMiePhase(a, nu) : shared::IsotropicPhaseFunction();
          luminance = vec3(glm::vec3(ray.samples.SumSunlight(mu_s, nu, ray.rayleigh_weight.data(),
                                                             static_cast<float>(rayleigh_phase), ray.mie_weight.data(),
                                                             static_cast<float>(mie_phase), nullptr)));
          if (ray.hits_ground) {
            luminance += ray.ground_throughput * shared::GetTransmittanceToSun(a, transmittance, a.bottom_radius, mu_s_g) *
                         a.ground_albedo * (std::max(mu_s_g, 0.0) / shared::kPi);
          }
        } else {
          // As shared::IntegrateMultiScatteringGatherRay.
          luminance = vec3(glm::vec3(ray.samples.SumMultipleScattering(mu_s, nu, ray.scattering_weight.data())));
          if (ray.hits_ground) {
            luminance += ray.ground_throughput * a.ground_albedo / shared::kPi *
                         shared::GetGatheredGroundIrradiance(ground_irradiance, mu_s_g);
          }
        }
        luminance_sum += luminance * ray.weight;
        if (ray.direction.z > 0.0) irradiance_sum += luminance * (ray.weight * ray.direction.z);
      }
      next[static_cast<std::size_t>(y) * size.x + x] = luminance_sum / double(count);
      if (y == 0) next_ground_irradiance[x] = shared::GetGatheredGroundIrradianceFromSum(irradiance_sum, count);
    }
  };
  const auto finish_order = [&] {
    order.swap(next);
    for (int x = 0; x < size.x; ++x) {
      ground_irradiance.at(x, 0) = glm::vec3(shared::EncodeMultiScattering(next_ground_irradiance[x]));
    }
  };

  const auto first_directions = directions_of(direction_count);
  if (gathered_orders == 1) {
    // Hillaire 2020's series: each row's rays live only while the row is computed.
    ForEachRow(size.y, [&](int y) {
      std::vector<MultipleScatteringRay> rays;
      f_ms[y] = build_row(y, first_directions, direction_count, rays);
      gather_row(1, y, rays, direction_count);
    });
    finish_order();
  } else {
    const bool own_set = gather_direction_count != direction_count;
    std::vector<std::vector<MultipleScatteringRay>> first_rays(size.y), gather_rays(own_set ? size.y : 0);
    const auto gather_directions = own_set ? directions_of(gather_direction_count) : first_directions;
    ForEachRow(size.y, [&](int y) {
      f_ms[y] = build_row(y, first_directions, direction_count, first_rays[y]);
      if (own_set) build_row(y, gather_directions, gather_direction_count, gather_rays[y]);
    });
    const auto& gathering = own_set ? gather_rays : first_rays;
    ForEachRow(size.y, [&](int y) { gather_row(1, y, first_rays[y], direction_count); });
    finish_order();
    sum = order;
    for (int n = 2; n <= gathered_orders; ++n) {
      for (std::size_t k = 0; k < texel_count; ++k) {
        previous_order.texels[k] = glm::vec4(glm::vec3(shared::EncodeMultiScattering(order[k])), 0.0f);
      }
      ForEachRow(size.y, [&](int y) { gather_row(n, y, gathering[y], gather_direction_count); });
      finish_order();
      for (std::size_t k = 0; k < texel_count; ++k) sum[k] += order[k];
    }
  }

  for (int y = 0; y < size.y; ++y) {
    for (int x = 0; x < size.x; ++x) {
      const std::size_t k = static_cast<std::size_t>(y) * size.x + x;
      const vec3 psi = gathered_orders == 1 ? shared::GetMultiScatteringFromMeans(order[k], f_ms[y])
                                            : shared::GetMultiScatteringFromOrders(sum[k], order[k], f_ms[y]);
      table.at(x, y) = glm::vec3(shared::EncodeMultiScattering(psi));
    }
  }
}

void ComputeSkyViewTable(const shared::AtmosphereParameters& a, const shared::Texture2D& transmittance,
                         const shared::Texture2D& multiple_scattering, double r, double mu_s, int sample_count,
                         shared::Texture2D& table) {
  const shared::ivec2 size(table.width, table.height);
  const PaddedTable padded_transmittance(transmittance);
  const PaddedTable padded_multiple_scattering(multiple_scattering);
  ForEachRow(size.y, [&](int y) {
    // The view zenith of the row; the columns only change the azimuth from the sun.
    double mu, unused_azimuth;
    shared::GetViewAnglesFromSkyViewTextureUv(a, size, r, vec2(0.5, y + 0.5) / vec2(size), mu, unused_azimuth);
    // The ground half of the rows holds the rays that meet the ground (as in shared::ComputeSkyViewTexel).
    const bool hits_ground = 2 * y >= size.y;
    const double t_max = shared::DistanceToNearestAtmosphereBoundary(a, r, mu, hits_ground);
    const ScatteringRay ray(a, padded_transmittance, padded_multiple_scattering, r, mu, t_max, sample_count);
    // Column x and column (width - x) see azimuths phi and 2 pi - phi: the same nu.
    for (int x = 0; 2 * x <= size.x; ++x) {
      double unused_mu, azimuth;
      shared::GetViewAnglesFromSkyViewTextureUv(a, size, r, vec2(x + 0.5, y + 0.5) / vec2(size), unused_mu, azimuth);
      const double nu = shared::SafeSqrt(1.0 - mu * mu) * shared::SafeSqrt(1.0 - mu_s * mu_s) * std::cos(azimuth) +
                        mu * mu_s;
      const glm::vec3 radiance(ray.Radiance(a, mu_s, nu));
      table.at(x, y) = radiance;
      table.at((size.x - x) % size.x, y) = radiance;
    }
  });
}

void ComputeGroundIrradianceTable(const shared::AtmosphereParameters& a, const shared::Texture2D& transmittance,
                                  const shared::Texture2D& multiple_scattering, int direction_count, int sample_count,
                                  shared::Texture2D& table) {
  const PaddedTable padded_transmittance(transmittance);
  const PaddedTable padded_multiple_scattering(multiple_scattering);
  const int width = table.width;
  std::vector<double> mu_s(width);
  for (int x = 0; x < width; ++x) mu_s[x] = shared::GetGroundIrradianceTexelMuS(width, x + 0.5);
  // The directions of shared::ComputeGroundIrradianceTerm (shared::GetGroundIrradianceDirection):
  // each one's ray from the ground, which no sun changes, is marched once and gives the term of
  // every texel. In parallel over directions, a block at a time; the terms are then added per
  // texel in the kernel's order.
  constexpr int kBlock = 256;
  std::vector<vec3> sums(width, vec3(0.0)), terms;
  for (int first = 0; first < direction_count; first += kBlock) {
    const int count = std::min(kBlock, direction_count - first);
    terms.assign(static_cast<std::size_t>(count) * width, vec3(0.0));
    oneapi::tbb::parallel_for(0, count, [&](int j) {
      const vec3 direction = shared::GetGroundIrradianceDirection(first + j, direction_count);
      const double z = direction.z;
      // As shared::IntegrateScatteredRadiance from the ground: inside, a ray that never meets it.
      const double t_max = shared::DistanceToNearestAtmosphereBoundary(a, a.bottom_radius, z, false);
      const ScatteringRay ray(a, padded_transmittance, padded_multiple_scattering, a.bottom_radius, z, t_max,
                              sample_count);
      for (int x = 0; x < width; ++x) {
        const vec3 sun(shared::SafeSqrt(1.0 - mu_s[x] * mu_s[x]), 0.0, mu_s[x]);
        terms[static_cast<std::size_t>(j) * width + x] =
            z * vec3(glm::vec3(ray.Radiance(a, mu_s[x], glm::dot(direction, sun))));
      }
    });
    for (int j = 0; j < count; ++j) {
      for (int x = 0; x < width; ++x) sums[x] += terms[static_cast<std::size_t>(j) * width + x];
    }
  }
  for (int x = 0; x < width; ++x) table.at(x, 0) = glm::vec3(shared::GetGroundIrradianceFromSum(sums[x], direction_count));
}

}  // namespace atmo::cpu
