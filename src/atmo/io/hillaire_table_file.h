// What the CPU and the GL computation of hillaire's exported tables share (private side of
// include/atmo/hillaire_tables.h).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "atmo/aerial_perspective.h"
#include "atmo/hillaire_tables.h"
#include "models/hillaire_model.h"

namespace atmo {

// Every hillaire setting as KEY=VALUE strings of its --option keys.
std::vector<std::pair<std::string, std::string>> HillaireTableOptions(const HillaireSettings& settings);

// Throws atmo::Error (one line) for a view the export cannot take: an altitude that is not
// finite or outside [0, top - ground], non-finite sun angles, a camera that is not perspective or
// fails ValidateCamera, bad aerial-perspective settings.
void ValidateHillaireExportView(const AtmosphereParameters& parameters, const HillaireExportView& view);

// The aerial_radiance (radiance = true) or aerial_transmittance table of a volume with
// `channel_count` channels, in batches of three (the last one repeating its last channel).
ExportedTable AerialPerspectiveTable(const AerialPerspectiveVolume& volume, bool radiance);

}  // namespace atmo
