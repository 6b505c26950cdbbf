#pragma once

#include "core/image.h"
#include "represent/model/representation.h"

namespace photomat {

// Synthesised gradient maps are copied block by block, so along the seams p and q need not be the
// derivatives of any surface. Before a height map is exported, the normal maps of a Gradient
// stack can be replaced by the nearest integrable field (represent/surface_integration.h:
// normals -> (p, q) -> ProjectToIntegrable -> normals), so that the relit maps and the height
// agree. The projection is periodic (Frankot-Chellappa), exact for tileable outputs.

// Whether the representation stores normals as maps ("normal.X", "normal.Y", "normal.Z").
bool HasNormalMaps(const Representation& representation);

// The representation with its normal maps projected onto the nearest integrable field (other
// maps unchanged; the details gain "integrable_projection": true). Throws Error if it has no
// normal maps.
Representation ProjectNormalsToIntegrable(const Representation& representation);

// A height map ("height", pixel units, zero mean) by Frankot-Chellappa from the normal maps, or
// from the normals the representation gives (EstimateNormals: 3I, PTM). Throws Error if it gives
// none (Eigen-k).
Image HeightFromRepresentation(const Representation& representation);

}  // namespace photomat
