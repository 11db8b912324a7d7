// Surface patches (McLaurin 2012, §2.6, §3.1): after intersect-and-split
// the meshes are cut into patches bounded by the intersection curves. This
// paints them (flood fill bounded by curves, borders, non-manifold edges and
// optional surface-group boundaries), classifies each against every input
// part with generalized winding numbers (robust to holes and to a part's own
// folds), and extracts the patches a boolean result keeps.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "common/base/json.h"
#include "common/base/mesh.h"

namespace meshmend {

// Per-face data that bounds patches and tells the parts apart. Empty
// vectors mean "none" (one part; no curves; no colours).
struct FaceLabels {
  std::vector<int> part;                  // the input layer each face came from (0, 1, ...)
  std::vector<std::uint8_t> curve_edges;  // bit i: edge from corner i to i+1 is a curve edge
  std::vector<std::uint32_t> colour;      // face colour (RGBA), for at_colour_changes
};

struct PaintOptions {
  bool at_curves = true;           // marked curve edges (intersect-and-split) bound patches
  bool at_borders = true;          // free edges (one face) bound patches (always: nothing across)
  bool at_non_manifold = true;     // edges of three or more faces bound patches
  bool at_colour_changes = false;  // an edge between faces of different colour bounds patches
  double crease_angle_deg = 0;     // > 0: an edge whose dihedral angle exceeds this bounds patches
};

struct Patch {
  int part = 0;  // the part (input layer) of its faces
  std::size_t faces = 0;
  double area = 0;
  int first_face = 0;  // its face of smallest index
  // Classification (classifyPatches): the winding number of each part at
  // the patch (its own part included, seen from on the patch: ½ more or
  // less than on either side), and of all parts together just outside
  // (along the face normals) and just inside the patch.
  std::vector<double> winding;
  // Per part: +1 where the patch lies on that part's surface facing the same
  // way (its own part; another part's copy of a planar overlap), -1 facing
  // the other way (two parts touching), 0 off it. On such a part's surface
  // the winding number is ½ more behind the patch (against its normal) than
  // on it, and ½ less in front, or the reverse when facing the other way.
  std::vector<std::int8_t> coincident;
  double windingInFront(int part) const { return winding[part] - 0.5 * coincident[part]; }
  double windingBehind(int part) const { return winding[part] + 0.5 * coincident[part]; }
  double winding_outside = 0, winding_inside = 0;  // all parts' together, in front and behind
  void setSideWindings() {
    winding_outside = winding_inside = 0;
    for (int p = 0; p < int(winding.size()); ++p) {
      winding_outside += windingInFront(p);
      winding_inside += windingBehind(p);
    }
  }
  // Inside another part on both sides (not on its surface).
  bool inside(int otherPart) const {
    return windingInFront(otherPart) > 0.5 && windingBehind(otherPart) > 0.5;
  }
  // Inside (or, with inside = false, outside) every part but its own and `except`.
  bool insideAllOthers(bool inside, int except = -1) const {
    for (int p = 0; p < int(winding.size()); ++p)
      if (p != part && p != except && this->inside(p) != inside) return false;
    return true;
  }
  // Is the patch part of the outer surface of the union of all parts?
  bool onUnionSurface() const { return winding_outside < 0.5 && winding_inside > 0.5; }
};

struct Patches {
  std::vector<int> patch_of_face;  // per face: its patch id
  std::vector<Patch> patches;  // by id: in the order of their first faces, then pieces split off
  int parts = 1;
  std::vector<bool> part_closed;  // per part: no border edge (after classifyPatches)
  // Per part (after classifyPatches): closed with its faces pointing inward
  // (a negative volume, as some scans and exports come), so that its winding
  // number is -1 inside. It is classified as if turned outward, and the
  // booleans turn its kept patches so that the result faces out.
  std::vector<bool> part_inside_out;
  std::size_t boundary_edges = 0;  // edges that bound patches
  // Patches classifyPatches found on both sides of an open part (a curve
  // that ends at the part's border does not separate them) and split where
  // that part's winding number crosses ½; the pieces get new ids.
  std::size_t patches_split_at_open_parts = 0;
};

// Flood-fills the faces of `mesh` into patches. A mesh with no boundaries of
// any kind is one patch per connected component. Throws InvalidInputError
// when `labels` do not match the mesh.
Patches paintPatches(const Mesh& mesh, const FaceLabels& labels, const PaintOptions& options = {});

// Patches as stored earlier (a patch id per face, e.g. read back from a
// MeshLab attribute): ids are renumbered in order of first appearance.
// Throws InvalidInputError for a negative id or a size mismatch.
Patches patchesFromIds(const Mesh& mesh, const FaceLabels& labels, const std::vector<int>& ids);

// Fills each patch's winding numbers. A closed part's winding number is an
// integer away from its surface; an open part's (a scan with holes) is
// fractional near the holes, and a patch counts as inside it above ½.
void classifyPatches(const Mesh& mesh, const FaceLabels& labels, Patches& patches);

enum class BooleanOperation {
  kUnion,         // the outer surface of all parts together
  kIntersection,  // the surface of the region inside every part
  kDifference,    // part 0 minus all the others
};
const char* toString(BooleanOperation op);
inline constexpr int kBooleanOperations = 3;

// Which patches the boolean result keeps, and which of those it turns over
// (the other parts' patches that bound a difference).
struct PatchChoice {
  std::vector<char> keep, flip;  // by patch id
};
PatchChoice choosePatches(const Patches& patches, BooleanOperation op);

// The faces of the kept patches as one mesh (flipped ones turned over),
// unused vertices dropped and exactly coincident vertices welded, so that
// patches of different layers that met along a curve join there.
// Provenance (the input's own, if any) is kept.
Mesh extractPatches(const Mesh& mesh, const Patches& patches, const std::vector<char>& keep,
                    const std::vector<char>& flip = {});

// The log table and report: id, part, faces, area, windings, status.
JsonObject toJson(const Patches& patches);
std::string statusOf(const Patch& patch, int parts);

// A colour per patch id, well separated from its neighbours in id order
// (hues a golden angle apart, alternating saturation): RGB.
std::array<std::uint8_t, 3> patchColour(int id);

// Per-face attribute names the MeshLab filters use between steps.
inline constexpr const char* kPatchAttribute = "meshmend_patch";  // int: patch id
inline constexpr const char* kPartAttribute = "meshmend_part";    // int: input layer

}  // namespace meshmend
