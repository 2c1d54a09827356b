// `toposimp check`: compares an original dataset with a simplified one — made by any tool — and
// reports what the simplification broke. The only part of toposimp that uses GEOS.
//
// Who decides: GEOS checks polygon validity (IsValidOp: reason and location) and computes where
// two segments meet; every yes/no question about contacts, sides and containment is decided by
// the exact predicates of src/core (a float filter, GMP when it cannot decide), so no answer
// depends on rounding. Each violation says which one decided.
#pragma once

#include "core/map/grid_step.hpp"

#include <cstdint>
#include <map>
#include <span>
#include <optional>
#include <string>
#include <vector>

namespace toposimp::io {
struct MemoryLayers;
}

namespace toposimp::validate {

struct CheckOptions {
    std::string original;
    std::string simplified;
    std::string points;              // control points: FILE or FILE:LAYER; empty: none
    std::string key;                 // match features by this field; empty: by order
    std::vector<std::string> layers; // layers to compare; empty: every layer of the original
    std::string simplified_layer;    // the simplified dataset's layer to compare with the one
                                     // original layer, whatever its name; empty: match by name
    std::optional<map::OutputGrid> grid;  // the simplified output was rounded onto this grid
                                        // (toposimp map --precision): a simplified vertex on the
                                        // grid matches an original vertex whose nearest grid
                                        // point is at most two steps away in x and in y
};

// What a simplification can break, in report order. Their names and meanings: kinds().
enum class ViolationKind {
    feature_lost,
    parts_changed,
    not_subset,
    ring_collapsed,
    ring_flipped,
    invalid_polygon,
    new_crossing,
    lost_crossing,
    new_touching,
    lost_touching,
    new_coincidence,
    border_no_longer_shared,
    point_changed_polygon,
    point_changed_side,
};

struct KindInfo {
    ViolationKind kind;
    const char* name;     // as reports write it: "new_crossing"
    const char* meaning;  // for people
};

// Every kind, in report order, with its name and meaning: the one table of them.
std::span<const KindInfo> kinds();
const char* name(ViolationKind kind);

struct Violation {
    ViolationKind kind;
    std::string layer;
    std::string feature;     // key value, or feature index
    std::string other;       // the other feature (contacts), or empty
    double x = 0, y = 0;     // where
    std::string detail;
    std::string decided_by;  // "exact" or "GEOS"
};

struct CheckReport {
    std::vector<Violation> violations;
    std::uint64_t features = 0;
    std::uint64_t control_points = 0;
    std::uint64_t invalid_in_original = 0;  // invalid polygons already invalid before: not counted

    bool clean() const { return violations.empty(); }
    // How many of each kind (every kind, none left out), by name in alphabetical order, as the
    // reports list them.
    std::map<std::string, std::uint64_t> counts() const;
};

// Throws io::InputError for unreadable or mismatched input.
CheckReport check(const CheckOptions& options);

// The same on layers in memory (the Python module; `points` may be null): `options`' original,
// simplified and points are set to GeoPackages in GDAL's memory file system, there for the call.
CheckReport check(const io::MemoryLayers& original, const io::MemoryLayers& simplified, const io::MemoryLayers* points,
                  CheckOptions options);

}  // namespace toposimp::validate
