// Conversion of the public AtmosphereParameters to the struct of the GLSL/C++ common subset.
#pragma once

#include <cstddef>
#include <span>

#include "atmo/parameters.h"
#include "shared/shared.h"

namespace atmo {

// Channels are evaluated three at a time (a vec3); this many batches cover all channels.
inline std::size_t ChannelBatchCount(std::size_t channel_count) { return (channel_count + 2) / 3; }

// The common subset's identifier (kPhase...) of a phase function.
int ToSharedPhase(PhaseFunction phase);

// Writes per-batch vec3 values into per-channel outputs: for every batch b, f(b) -> vec3 gives
// channels 3b .. 3b + 2 (those that exist).
template <typename F>
void ScatterBatches(std::size_t batch_count, std::span<double> out, const F& f) {
  for (std::size_t b = 0; b < batch_count; ++b) {
    const shared::vec3 v = f(b);
    for (std::size_t c = 0; c < 3 && 3 * b + c < out.size(); ++c) out[3 * b + c] = v[static_cast<int>(c)];
  }
}

// The values of channels [3 * batch, 3 * batch + 3) of a per-channel list (the solar irradiance,
// say); a batch with fewer than three channels repeats its last one, as ToSharedParameters does.
shared::vec3 BatchValues(std::span<const double> values, std::size_t batch);

// The shared parameters for channels [3 * batch, 3 * batch + 3) of a spherical atmosphere; a batch
// with fewer than three channels repeats its last one. `length_unit_m` is the length unit of the
// result in metres (1 on the CPU, 1000 for the km of the GPU). Throws atmo::Error for what the
// common subset cannot express (a scattering ozone layer).
shared::AtmosphereParameters ToSharedParameters(const AtmosphereParameters& parameters, std::size_t batch,
                                                double length_unit_m = 1.0);

}  // namespace atmo
