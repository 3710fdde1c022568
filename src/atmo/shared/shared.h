// Includes the GLSL/C++ common subset as C++ (double precision) in namespace atmo::shared.
//
// The host/GPU structs have external linkage and are the same type in every translation unit;
// the functions get internal linkage (an unnamed namespace), because GLSL has no `inline` and the
// same source must be valid in both languages.
#pragma once

#include "glsl_cpp.h"

// Each translation unit uses only some of the functions.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"

namespace atmo::shared {
#include "definitions.glsl"
namespace {
#include "geometry.glsl"
#include "medium.glsl"
#include "phase.glsl"
#include "transmittance.glsl"
#include "multiple_scattering.glsl"
#include "sun.glsl"
#include "sky.glsl"
#include "camera.glsl"
#include "tables.glsl"
#include "elek.glsl"
#include "simple.glsl"
#include "source4d.glsl"
}  // namespace
}  // namespace atmo::shared

#pragma GCC diagnostic pop
