// Sampled Hausdorff distance between two triangle meshes (a measurement, not a predicate: plain
// doubles). Samples: every vertex, plus points spread over each face in proportion to its area.
#pragma once

#include "core/mesh/mesh.hpp"

#include <cstddef>

namespace toposimp::mesh {

struct OneWayDistance {
    double max = 0.0;   // largest distance from a sample of one mesh to the other mesh
    double mean = 0.0;
    std::size_t samples = 0;
};

struct HausdorffDistance {
    OneWayDistance forward;   // from the first mesh to the second
    OneWayDistance backward;  // from the second to the first
    double diagonal = 0.0;    // of the first mesh's bounding box
    double max() const { return forward.max > backward.max ? forward.max : backward.max; }
};

// `face_samples`: about how many points to spread over each mesh's faces (plus its vertices).
// `threads`: 0 for OpenMP's default; the result is the same for any.
HausdorffDistance hausdorff(const Mesh& a, const Mesh& b, std::size_t face_samples = 200000, int threads = 0);

// Vertical error between two terrains (faces triangulating the x–y plane): from each sample of
// one (the same samples as hausdorff's), |Δz| to the other's surface straight above or below it
// (the face holding its x–y position, by exact orientation tests; z interpolated in doubles).
// Samples with no face of the other above or below them are counted, not measured.
struct VerticalError {
    OneWayDistance forward;   // from the first terrain's samples to the second's surface
    OneWayDistance backward;  // from the second's to the first's
    std::size_t outside = 0;  // samples of either outside the other's x–y extent
    double max() const { return forward.max > backward.max ? forward.max : backward.max; }
};
VerticalError vertical_error(const Mesh& a, const Mesh& b, std::size_t face_samples = 200000, int threads = 0);

}  // namespace toposimp::mesh
