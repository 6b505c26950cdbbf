#pragma once

#include "synthesize/mesh/mesh.h"

namespace photomat {

// Loop subdivision (Loop 1987): each level splits every triangle into four and moves the vertices
// by Loop's masks (edge points 3/8, 3/8, 1/8, 1/8; vertex points Loop's beta for valence n; the
// cubic B-spline rules along boundary edges). Repeated, the positions converge to the Loop limit
// surface that Bajaj, Zhang and Xu use as their finite-element basis; solving P1 elements on the
// refined mesh approximates that basis. Vertices keep their indices: the first vertex_count()
// vertices of the result are the (moved) input vertices.
TriangleMesh LoopSubdivide(const TriangleMesh& mesh, int levels = 1);

}  // namespace photomat
