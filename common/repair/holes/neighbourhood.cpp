#include "common/repair/holes/neighbourhood.h"

#include <cstdint>
#include <memory>

#include "common/base/parallel.h"
#include "common/exact/box_tree.h"

namespace meshmend::holes {

std::vector<std::vector<int>> inputFacesNear(const Mesh& mesh, const std::vector<Bounds>& regions,
                                             bool& finite) {
  std::vector<std::vector<int>> out(regions.size());
  finite = true;
  if (regions.empty()) return out;
  Bounds all;
  for (const Bounds& r : regions) all.add(r);
  // Per point, the sides of the regions' common box it lies beyond (a bit
  // per side and axis): a face whose corners share a bit lies beyond that
  // side with all of it, away from every region, as most of a large mesh does.
  const Vertex* vert = mesh.vert.data();
  std::vector<std::uint8_t> beyond(mesh.vert.size());
  std::vector<double> notFinite(workerCount(), 0);  // x - x is 0 for finite x, else NaN
  parallelChunks(
      mesh.vert.size(),
      [&](std::size_t begin, std::size_t end, unsigned worker) {
        double sum = 0;
        const double lo0 = all.lo[0], lo1 = all.lo[1], lo2 = all.lo[2];
        const double hi0 = all.hi[0], hi1 = all.hi[1], hi2 = all.hi[2];
        std::uint8_t* code = beyond.data();  // a local: byte stores could alias anything
        for (std::size_t v = begin; v < end; ++v) {
          const Point3& p = positionOf(vert[v]);
          const double x = p[0], y = p[1], z = p[2];
          sum += (x - x) + (y - y) + (z - z);
          code[v] = std::uint8_t(unsigned(x < lo0) | unsigned(y < lo1) << 1 |
                                 unsigned(z < lo2) << 2 | unsigned(x > hi0) << 3 |
                                 unsigned(y > hi1) << 4 | unsigned(z > hi2) << 5);
        }
        notFinite[worker] = sum;
      },
      1 << 14);
  for (double sum : notFinite) finite = finite && sum == 0;
  if (!finite) return out;
  // The regions in a hierarchy of their boxes when there are many.
  std::unique_ptr<BoxTree> tree;
  if (regions.size() > 8) {
    std::vector<Box> boxes;
    for (const Bounds& r : regions) {
      const Box lo = boxOf(r.lo), hi = boxOf(r.hi);
      boxes.push_back({{lo.lo[0], lo.lo[1], lo.lo[2]}, {hi.hi[0], hi.hi[1], hi.hi[2]}});
    }
    tree = std::make_unique<BoxTree>(std::move(boxes));
  }
  const Face* faces = mesh.face.data();
  std::vector<std::vector<std::pair<int, int>>> found(workerCount());  // (region, face)
  parallelChunks(
      mesh.face.size(),
      [&](std::size_t begin, std::size_t end, unsigned worker) {
        const std::uint8_t* code = beyond.data();
        for (std::size_t f = begin; f < end; ++f) {
          const Face& face = faces[f];
          const Vertex *a = face.cV(0), *b = face.cV(1), *c = face.cV(2);
          if (code[a - vert] & code[b - vert] & code[c - vert]) continue;
          const Point3 &pa = positionOf(*a), &pb = positionOf(*b), &pc = positionOf(*c);
          Bounds box;
          box.add(pa);
          box.add(pb);
          box.add(pc);
          if (tree) {
            tree->query(boxOf(pa, pb, pc), worker, [&](std::uint32_t r, unsigned) {
              if (regions[r].overlaps(box)) found[worker].push_back({int(r), int(f)});
            });
            continue;
          }
          for (std::size_t r = 0; r < regions.size(); ++r)
            if (regions[r].overlaps(box)) found[worker].push_back({int(r), int(f)});
        }
      },
      1 << 14);
  // Chunks run over ascending ranges of faces: in worker order, each list ascends.
  for (const auto& part : found)
    for (const auto& [r, f] : part) out[std::size_t(r)].push_back(f);
  return out;
}

}  // namespace meshmend::holes
