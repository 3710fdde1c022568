// Conversion of the public Camera to the shared camera kernel's parameters (private).
#pragma once

#include <span>

#include "atmo/render.h"
#include "shared/shared.h"

namespace atmo {

shared::CameraParameters ToSharedCamera(const Camera& camera);
// Throws atmo::Error for a resolution outside [1, kMaxImageSide], non-finite angles or a
// perspective field of view outside (0, 180) degrees.
void ValidateCamera(const Camera& camera);

// The view directions of row `row` of a perspective camera, as shared::GetCameraRayDirection gives
// them (to rounding), with the work common to the row done once.
void PerspectiveRowDirections(const shared::CameraParameters& camera, int row, std::span<glm::dvec3> views);

}  // namespace atmo
