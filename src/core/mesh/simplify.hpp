// UGSimp: parallel quadric-error edge collapse that never creates a self-intersection, a
// flipped face or a non-manifold edge (dissertation chapter 4, extended).
//
// The mesh is overlaid with a 3D uniform grid whose cells are grouped into blocks; a level's
// blocks are simplified in parallel, each with its own binary heap of edges ranked by the
// Garland–Heckbert quadric error. An edge is a candidate in a block only when both ends and all
// their neighbours lie in the block, and the merged vertex is placed inside the block too: every
// face a collapse changes, and every face it is tested against that another thread could change,
// then lie in separate blocks. When a level has done what it can, blocks are merged 2×2×2 and
// the next level runs, up to one block. Every collapse is checked before it is made, with exact
// predicates (float filter, GMP fallback): link condition, no face flipped (normal reversed, or
// for terrain, orientation in the map plane changed), no degenerate or duplicate face, and no
// contact between a new face and any other face except along the corners they share.
// (simplifier.hpp lists the files the method's steps live in.)
#pragma once

#include "core/exact/predicates.hpp"
#include "core/mesh/mesh.hpp"

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>

namespace toposimp::mesh {

enum class Target {
    keep_fraction,  // keep this share of the faces
    keep_faces,     // keep this many faces
    // Collapse while the error stays at most this. For a terrain (SimplifyOptions::terrain, and
    // the faces do triangulate the map plane): the vertical distance between the input and the
    // output surface, everywhere, guaranteed by exact tests (vertical_bound.hpp); the border is
    // then kept as it is. Otherwise the quadric error (a distance in the mesh's units).
    max_error,
};

// When to stop collapsing (as map::StopCriterion says when to stop removing vertices).
struct StopCriterion {
    Target target = Target::keep_fraction;
    double value = 0.1;
};

// How a mesh is kept free of new contacts between its faces. (A terrain whose border is kept
// needs neither: no collapse of it can make one. One whose border may move is checked in the map
// plane, either way.)
enum class ContactCheck {
    // Each collapse is made without searching for the faces near its new ones; the result is
    // then checked once, exactly: every pair of nearby faces one of which a collapse made
    // (find_self_contact; two faces of the input that still meet are the input's contact). If a
    // pair meets (a collapse made a contact, or a new face meets one the input's faces met), the
    // mesh is simplified again from the input as every_collapse does. Either way the result has
    // no new contact; it is every_collapse's result whenever every_collapse refuses no collapse
    // for a contact (then both make the same collapses), and it costs the check and, rarely, a
    // second run instead of a search at every collapse (on smooth scans most of the
    // simplification's time).
    at_the_end,
    // Each collapse searches the faces near its new ones and is refused if one would meet another
    // face beyond their shared corners (contacts.cpp); a contact the input had may be inherited.
    every_collapse,
};

struct SimplifyOptions {
    StopCriterion stop;
    ContactCheck contacts = ContactCheck::at_the_end;
    // Border vertices (on an edge with one face) never move and are never removed.
    bool lock_boundary = false;
    // The faces triangulate the map plane (a terrain TIN, z = height): a collapse must keep every
    // face's orientation in the x–y plane. The surface then stays a height field over a valid
    // planar triangulation, which cannot self-intersect, so no 3D intersection search is needed.
    bool terrain = false;
    // The terrain is known to be a height field (a DEM's TIN): no two faces overlap in the map
    // plane. Otherwise that is checked, exactly (height_field.hpp: work on the border edges, which
    // the simplifier finds in its pass over each vertex's faces anyway, ~20 ms on the 2 M-face
    // terrain; pairs of nearby faces, ~0.65 s there, when the border cannot tell), and a mesh
    // that fails it is simplified in space.
    bool height_field = false;
    // A collapse inside a flat region whose faces are all known clean may be shown free of contacts
    // without searching for nearby faces (same decision, same result; off: always search — for
    // the tests that compare the two).
    bool flat_shortcut = true;
    int threads = 0;  // 0: OpenMP's default
    // Meshes with fewer faces run on one thread (results are identical either way).
    std::size_t parallel_threshold = std::size_t{1} << 14;
    // Called on the calling thread after every round with the share of the work done (0…1):
    // faces removed of those to remove for count targets, levels done for --max-error.
    std::function<void(double done)> progress;
    // Called on the calling thread when a later phase of the work begins (ContactCheck::at_the_end:
    // "checking the result for contacts", then maybe "simplifying again, every collapse
    // checked"); progress() then counts that phase from 0. May be empty.
    std::function<void(const char* phase)> phase;
    // Set by the caller to stop: the engine then throws Cancelled (core/cancel.hpp) between two
    // rounds, the mesh left half simplified (not a result to use). May be null.
    const std::atomic<bool>* cancel = nullptr;
};

struct SimplifyStats {
    std::uint64_t vertices_in = 0, vertices_out = 0;
    std::uint64_t faces_in = 0, faces_out = 0;
    std::uint64_t target_faces = 0;  // count targets only
    bool target_reached = false;
    std::uint64_t collapses = 0;
    // Collapses refused, by reason.
    std::uint64_t refused_link = 0;          // link condition: would make a non-manifold edge or vertex
    std::uint64_t refused_boundary = 0;      // would pinch a border or move a locked vertex
    std::uint64_t refused_flip = 0;          // a face would turn over (3D normal, or map-plane fold)
    std::uint64_t refused_degenerate = 0;    // a face would lose its area or duplicate another
    std::uint64_t refused_intersection = 0;  // a new face would touch or cross another face
    std::uint64_t refused_vertical = 0;      // the terrain would move more than the vertical bound
    std::uint64_t refused() const {
        return refused_link + refused_boundary + refused_flip + refused_degenerate + refused_intersection + refused_vertical;
    }
    // Simplified as a terrain (asked for, every face turned the same way in the map plane, and no
    // two overlapping there).
    bool terrain = false;
    // A terrain was asked for, but these two faces (numbered as in the input) overlap in the map
    // plane.
    std::optional<std::array<std::uint32_t, 2>> plan_overlap;
    // The input has an edge with more than two faces: the least (a < b, then by b), with its first
    // few faces in order, numbered as in the input. It was not simplified.
    std::optional<NonManifoldEdge> non_manifold;
    // The vertical distance to the input is at most the max_error target everywhere.
    bool vertical_bound = false;
    // Collapses in flat regions proven free of contacts without searching for nearby faces
    // (see flat_and_clean in contacts.cpp); included in `collapses`.
    std::uint64_t flat_unsearched = 0;
    // ContactCheck::at_the_end: the collapses were made without a contact search and the result
    // checked after (contacts_checked_after): every pair of faces with a face a collapse made (a
    // contact between two faces of the input is the input's). If that check found two faces
    // meeting (contact_near: a corner of one of them; or a degenerate face), the mesh was
    // simplified again from the input with every collapse checked (simplified_again; the counts
    // above are that run's). Neither for a terrain whose border is kept: it needs no search.
    bool contacts_checked_after = false;
    bool simplified_again = false;
    std::optional<Point3> contact_near;
    double seconds_first_run = 0.0;  // the run whose result met itself, and its check
    double seconds_check = 0.0;      // the check of the result (of the run that found a contact, if any)
    double max_error = 0.0;  // largest quadric error (distance) of a collapse made
    int levels = 0;
    int rounds = 0;  // heap builds over all levels (count targets repeat a level while it progresses)
    int threads = 1;
    double seconds_setup = 0.0, seconds_collapse = 0.0;
    exact::PredicateStats predicates;
};

// Simplifies `mesh` in place. Faces repeating a corner and vertices that no face uses are
// dropped. An input with a non-manifold edge is not simplified (SimplifyStats::non_manifold). The
// result keeps the surviving vertices in input order and the surviving faces in input order.
// Throws std::invalid_argument, the mesh untouched, if a corner index is out of range or an
// attribute table does not hold one row per vertex (face).
SimplifyStats simplify(Mesh& mesh, const SimplifyOptions& options);

}  // namespace toposimp::mesh
