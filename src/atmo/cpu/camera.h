// Conversion of the public Camera to the shared camera kernel's parameters (private).
#pragma once

#include "atmo/render.h"
#include "shared/shared.h"

namespace atmo {

shared::CameraParameters ToSharedCamera(const Camera& camera);
// Throws atmo::Error for a resolution outside [1, kMaxImageSide], non-finite angles or a
// perspective field of view outside (0, 180) degrees.
void ValidateCamera(const Camera& camera);

}  // namespace atmo
