// Generated meshes for property tests and benchmarks: closed surfaces, terrains, and the hard
// cases for intersection tests (sheets a few ulps apart, a strip folded onto itself).
#pragma once

#include "core/mesh/mesh.hpp"

#include <cstdint>

namespace toposimp::testing {

// A sphere of radius ~1 around `center`, subdivided icosahedron (20·4^level faces), each vertex
// moved radially by up to `noise` (relative).
mesh::Mesh noisy_sphere(int level, double noise, std::uint64_t seed, Point3 center = {0, 0, 0});

// A terrain: an n×n grid of unit cells, heights smooth hills plus noise of amplitude `noise`,
// counter-clockwise in the x–y plane.
mesh::Mesh noisy_heightfield(int n, double noise, std::uint64_t seed);

// Two wavy n×n sheets, the second the first lifted by `ulps` units in the last place of z
// (in the same binade), so any vertex moved off its sheet risks crossing the other one.
mesh::Mesh near_sheets(int n, int ulps, std::uint64_t seed);

// A long strip folded back over itself three times, the layers `gap` apart.
mesh::Mesh folded_strip(int length, double gap, std::uint64_t seed);

}  // namespace toposimp::testing
