// Renders a mesh to a picture (binary PPM; scripts convert it to PNG):
// flat-shaded faces seen along a direction, in one colour or coloured by
// surface patch (painted here with the core's defaults: curves of a merged
// intersect-and-split output are non-manifold edges, so the patches come
// out as the paint filter made them).
//
//   meshmend_render IN OUT.ppm [--patches] [--view X,Y,Z] [--size W,H]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "common/errors.h"
#include "common/mesh_io.h"
#include "common/patches.h"

using namespace meshmend;

namespace {

Point3 parseTriple(const char* text) {
  Point3 p(0, 0, 0);
  if (std::sscanf(text, "%lf,%lf,%lf", &p[0], &p[1], &p[2]) != 3)
    throw InvalidInputError(std::string("expected X,Y,Z, got '") + text + "'");
  return p;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    if (argc < 3) {
      std::fprintf(stderr, "usage: %s IN OUT.ppm [--patches] [--view X,Y,Z] [--size W,H]\n",
                   argv[0]);
      return 1;
    }
    bool patches = false;
    Point3 view(-1, -0.6, -1.6);  // from the front left, slightly above
    int width = 1200, height = 900;
    for (int i = 3; i < argc; ++i) {
      if (!std::strcmp(argv[i], "--patches")) {
        patches = true;
      } else if (!std::strcmp(argv[i], "--view") && i + 1 < argc) {
        view = parseTriple(argv[++i]);
      } else if (!std::strcmp(argv[i], "--size") && i + 1 < argc) {
        if (std::sscanf(argv[++i], "%d,%d", &width, &height) != 2 || width < 16 || height < 16)
          throw InvalidInputError("expected --size W,H (at least 16 each)");
      } else {
        throw InvalidInputError(std::string("unknown option ") + argv[i]);
      }
    }
    const Mesh mesh = readMesh(argv[1]);
    const std::vector<Point3> P = positionsOf(mesh);
    const std::vector<Triangle> T = trianglesOf(mesh);
    if (T.empty()) throw InvalidInputError(std::string(argv[1]) + " has no faces");
    std::vector<int> patchOf(T.size(), 0);
    if (patches) patchOf = paintPatches(mesh, {}).patch_of_face;

    // A camera frame: w along the view direction, u to the right, v up.
    Point3 w = view.Normalize(), up(0, 1, 0);
    if (std::fabs(w * up) > 0.99) up = Point3(0, 0, 1);
    const Point3 u = (up ^ w).Normalize(), v = (w ^ u).Normalize();
    double lo[2] = {HUGE_VAL, HUGE_VAL}, hi[2] = {-HUGE_VAL, -HUGE_VAL};
    for (const Point3& p : P) {
      lo[0] = std::min(lo[0], p * u), hi[0] = std::max(hi[0], p * u);
      lo[1] = std::min(lo[1], p * v), hi[1] = std::max(hi[1], p * v);
    }
    const double scale = 0.92 * std::min(width / (hi[0] - lo[0]), height / (hi[1] - lo[1]));
    auto project = [&](const Point3& p) {
      return Point3(width / 2.0 + (p * u - (lo[0] + hi[0]) / 2) * scale,
                    height / 2.0 - (p * v - (lo[1] + hi[1]) / 2) * scale, p * w);
    };
    std::vector<float> depth(std::size_t(width) * height, INFINITY);
    std::vector<unsigned char> image(std::size_t(width) * height * 3, 255);
    const Point3 light = (w * -1.0 + v * 0.6 + u * -0.3).Normalize();
    for (std::size_t f = 0; f < T.size(); ++f) {
      const Point3 a = project(P[T[f][0]]), b = project(P[T[f][1]]), c = project(P[T[f][2]]);
      Point3 n = (P[T[f][1]] - P[T[f][0]]) ^ (P[T[f][2]] - P[T[f][0]]);
      if (!(n.Norm() > 0)) continue;
      n.Normalize();
      const double shade = 0.25 + 0.75 * std::fabs(n * light);  // two-sided
      const auto base =
          patches ? patchColour(patchOf[f]) : std::array<std::uint8_t, 3>{200, 200, 190};
      const double area = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
      if (area == 0) continue;
      const int x0 = std::max(0, int(std::floor(std::min({a[0], b[0], c[0]}))));
      const int x1 = std::min(width - 1, int(std::ceil(std::max({a[0], b[0], c[0]}))));
      const int y0 = std::max(0, int(std::floor(std::min({a[1], b[1], c[1]}))));
      const int y1 = std::min(height - 1, int(std::ceil(std::max({a[1], b[1], c[1]}))));
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          const double px = x + 0.5, py = y + 0.5;
          const double l0 = ((b[0] - px) * (c[1] - py) - (c[0] - px) * (b[1] - py)) / area;
          const double l1 = ((c[0] - px) * (a[1] - py) - (a[0] - px) * (c[1] - py)) / area;
          const double l2 = 1 - l0 - l1;
          if (l0 < 0 || l1 < 0 || l2 < 0) continue;
          const float z = float(l0 * a[2] + l1 * b[2] + l2 * c[2]);
          const std::size_t i = std::size_t(y) * width + x;
          if (z >= depth[i]) continue;
          depth[i] = z;
          for (int k = 0; k < 3; ++k) image[3 * i + k] = (unsigned char)(base[k] * shade);
        }
    }
    std::ofstream out(argv[2], std::ios::binary);
    out << "P6\n" << width << " " << height << "\n255\n";
    out.write(reinterpret_cast<const char*>(image.data()), std::streamsize(image.size()));
    if (!out) throw InvalidInputError(std::string("cannot write ") + argv[2]);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "meshmend_render: %s\n", e.what());
    return 2;
  }
}
