// An independent, brute-force, exact checker of DESIGN.md's map promises, written for the tests
// only: it shares no predicate code with the engine (its own GMP orientation test) and looks at
// every pair it needs to, with nothing but exact bounding-box comparisons to skip work.
#pragma once

#include "core/map/map_data.hpp"

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace toposimp::testing {

int exact_orient(Point a, Point b, Point c);

// Do the closed segments pq and rs meet anywhere other than at a location that is an endpoint
// of both (or overlap along a stretch)? That is a contact a planar map must not have.
bool improper_contact(Point p, Point q, Point r, Point s);

struct CheckReport {
    std::vector<std::string> violations;
    bool ok() const { return violations.empty(); }
    std::string summary() const;
};

// Every chain keeps its first and last vertex; output segments meet only at common endpoints,
// unless both are segments of the input unchanged (their contact is the input's); every detour (removed sub-chain + replacing segment) holds no other output
// vertex or control point, neither inside (winding number or crossing parity) nor on it.
CheckReport check_simplification(const map::MapData& input, const std::vector<std::uint8_t>& kept);

// Is the input itself planar in the sense above (the precondition of the promises)?
CheckReport check_planar(const map::MapData& input);

// The promises for a simplified map written at positions `at` (rounded: not the input's): every
// chain keeps its ends (moved or not); per pair of chains, as many proper crossings and as many
// other contacts as in the input; each closed chain keeps at least 3 distinct corners, its
// orientation, and every control point inside, on or outside it as before; no control point
// lies inside the loop an open chain makes with its output (input forward, output back) or on
// it, other than on both; each output vertex is where `on_grid` accepts it or listed in
// `off_grid` at its input location.
CheckReport check_rounded(const map::MapData& input, const std::vector<std::uint8_t>& kept, const std::vector<Point>& at,
                          const std::function<bool(Point)>& on_grid);

// For each pair of chains (i < j, at i·n + j): how many proper crossings their kept segments have.
std::vector<std::uint64_t> crossings_between_chains(const map::MapData& map, const std::vector<std::uint8_t>& kept);

}  // namespace toposimp::testing
