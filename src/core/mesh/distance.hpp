// Sampled Hausdorff distance between two triangle meshes (a measurement, not a predicate: plain
// doubles). Samples: every vertex, plus points spread over each face in proportion to its area.
#pragma once

#include "core/mesh/mesh.hpp"

#include <cstddef>
#include <vector>

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

// The quick measure (toposimp mesh's default): `count` points of each mesh, spread over it by area
// (stratified, deterministic), each measured to the nearest face of the other exactly as
// hausdorff() measures; only the faces near the points are indexed, so the cost grows with
// `count`, not with the meshes (beyond a pass over their faces). The largest distance found is a
// lower bound of the Hausdorff distance; were the points independent uniform samples, the share
// of a surface farther than it from the other would exceed 0.1 % with probability 0.999^count
// (4.1e-4 for 8 192 points): share_beyond below.
HausdorffDistance spread_hausdorff(const Mesh& a, const Mesh& b, std::size_t count, int threads = 0);
// How many points the quick measure spreads over each mesh when the input has `faces` faces: one
// per 40 faces, at least 1 024 and at most 8 192. Its cost is about a pass over the input's faces
// and a search per point: under a tenth of the simplification's on the small models (8 192
// points took 15-28 % there).
std::size_t quick_points(std::size_t faces);
// The share of a surface farther from the other than the largest distance found from `points` of
// its points might be, at 99.9 % confidence, were they independent uniform samples: the s with
// (1 − s)^points = 0.001 (0.084 % for 8 192 points, 0.67 % for 1 024).
double share_beyond(std::size_t points);
// The points spread_hausdorff measures from `m` (for tests).
std::vector<Point3> spread_points(const Mesh& m, std::size_t count);

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
// The same from `count` points of each, spread as spread_hausdorff spreads them.
VerticalError spread_vertical_error(const Mesh& a, const Mesh& b, std::size_t count, int threads = 0);

// Both quick measures of two terrains at once, as spread_hausdorff and spread_vertical_error
// give them, for less: the nearest point of the other surface is no farther than the one
// straight above or below, so each point's distance in space is searched among the faces
// whose boxes in the map plane meet a square that small around it (the same index serves both);
// only the points with no face above or below them are searched in space.
struct TerrainMeasure {
    HausdorffDistance distance;
    VerticalError vertical;
};
TerrainMeasure spread_terrain_measure(const Mesh& a, const Mesh& b, std::size_t count, int threads = 0);

}  // namespace toposimp::mesh
