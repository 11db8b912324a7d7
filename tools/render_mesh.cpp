// Renders meshes, or the layers of a MeshLab project (.mlp, with their
// matrices), to a picture (binary PPM; scripts/render makes a PNG of it):
// flat-shaded faces seen along a direction, orthographic, 2x2 supersampled,
// coloured by what a repair changed. Works without MeshLab and without a
// display, so pictures are the same on every machine.
//
//   meshmend_render [options] INPUT... -o OUT.ppm
//
//   --colour plain         one colour (the default for one layer)
//   --colour layers        a colour per layer (the default for several)
//   --colour patches       a colour per surface patch, boundaries dark (the core's
//                          painting: curves of a merged split output are its
//                          non-manifold edges)
//   --colour intersecting  faces that intersect another face (exactly, within and
//                          between layers) red
//   --colour new-faces     faces that are not faces of --before (same corner
//                          coordinates) orange, their region outlined
//   --colour clearance     each vertex's clearance (exact distance to the nearest
//                          non-adjacent face, within and between layers): red below
//                          --tau, yellow to blue over --range (default tau to 3 tau)
//   --before FILE          the mesh or project before the repair (new-faces)
//   --tau T, --range LOW,HIGH   clearance threshold and colour range (mesh units)
//   --scope within|between|both which face pairs the clearance counts (default both)
//   --borders              border edges (used by one face) drawn red
//   --frame FILE           fit the view to FILE's bounds instead (same framing for
//                          a before and an after picture)
//   --focus X,Y,Z,R        fit the view to the ball of radius R around X,Y,Z (a close-up;
//                          the intersecting and clearance modes print where their red faces are)
//   --view X,Y,Z           viewing direction (default from the front left, above)
//   --size W,H             picture size in pixels (default 800,600)
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "common/repair/clearance/clearance.h"
#include "common/base/errors.h"
#include "common/exact/intersections.h"
#include "common/io/mesh_io.h"
#include "common/repair/patches/patches.h"

using namespace meshmend;

namespace {

using Colour = std::array<double, 3>;  // 0..1

// ---- the scene: layers in one frame ---------------------------------------------

struct Layer {
  std::string name;
  std::vector<Point3> points;  // transformed by the project's matrix
  std::vector<Triangle> triangles;
};

Point3 parseTriple(const std::string& text) {
  Point3 p(0, 0, 0);
  if (std::sscanf(text.c_str(), "%lf,%lf,%lf", &p[0], &p[1], &p[2]) != 3)
    throw InvalidInputError("expected X,Y,Z, got '" + text + "'");
  return p;
}

Layer loadLayer(const std::string& path, const std::array<double, 16>* matrix) {
  const Mesh mesh = readMesh(path);
  Layer layer{std::filesystem::path(path).filename().string(), positionsOf(mesh),
              trianglesOf(mesh)};
  if (matrix) {
    const auto& m = *matrix;  // row-major, as MeshLab writes it; points are columns
    for (Point3& p : layer.points) {
      const Point3 q = p;
      for (int r = 0; r < 3; ++r)
        p[r] = m[4 * r] * q[0] + m[4 * r + 1] * q[1] + m[4 * r + 2] * q[2] + m[4 * r + 3];
    }
  }
  return layer;
}

// A MeshLab project: each <MLMesh filename="..."> with its <MLMatrix44>,
// file names relative to the project. Every layer file must exist.
std::vector<Layer> loadProject(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InvalidInputError("cannot read the project " + path);
  std::stringstream text;
  text << in.rdbuf();
  const std::string xml = text.str();
  const std::regex meshPattern("<MLMesh\\b([^>]*)>([\\s\\S]*?)</MLMesh>");
  const std::regex filePattern("filename=\"([^\"]*)\"");
  const std::regex matrixPattern("<MLMatrix44>([^<]*)</MLMatrix44>");
  const std::filesystem::path dir = std::filesystem::path(path).parent_path();
  std::vector<Layer> layers;
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), meshPattern);
       it != std::sregex_iterator(); ++it) {
    const std::string attributes = (*it)[1], body = (*it)[2];
    std::smatch file, matrix;
    if (!std::regex_search(attributes, file, filePattern))
      throw InvalidInputError(path + ": a layer without a filename");
    std::array<double, 16> m = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    if (std::regex_search(body, matrix, matrixPattern)) {
      std::istringstream numbers(matrix[1].str());
      for (double& v : m)
        if (!(numbers >> v))
          throw InvalidInputError(path + ": a matrix with fewer than 16 numbers");
    }
    const std::filesystem::path layerPath = dir / file[1].str();
    if (!std::filesystem::exists(layerPath))
      throw InvalidInputError(path + " names " + layerPath.string() +
                              ", which does not exist: make a project of the layers at hand");
    layers.push_back(loadLayer(layerPath.string(), &m));
  }
  if (layers.empty()) throw InvalidInputError(path + " has no layers (<MLMesh> elements)");
  return layers;
}

std::vector<Layer> loadInputs(const std::vector<std::string>& paths) {
  std::vector<Layer> layers;
  for (const std::string& p : paths) {
    if (std::filesystem::path(p).extension() == ".mlp") {
      for (Layer& l : loadProject(p)) layers.push_back(std::move(l));
    } else {
      layers.push_back(loadLayer(p, nullptr));
    }
  }
  return layers;
}

// ---- colours ------------------------------------------------------------------

Colour rgb(const std::array<std::uint8_t, 3>& c) {
  return {c[0] / 255.0, c[1] / 255.0, c[2] / 255.0};
}

const Colour kPlain = {0.80, 0.80, 0.76};
const Colour kRed = {0.92, 0.10, 0.08};
const Colour kNew = {1.00, 0.55, 0.10};

// The clearance ramp of shaders/meshmend_clearance.frag.
Colour ramp(double t) {
  const Colour nearC = {1.0, 0.85, 0.1}, midC = {0.25, 0.75, 0.3}, farC = {0.2, 0.4, 0.95};
  const Colour& a = t < 0.5 ? nearC : midC;
  const Colour& b = t < 0.5 ? midC : farC;
  const double s = t < 0.5 ? 2 * t : 2 * t - 1;
  return {a[0] + (b[0] - a[0]) * s, a[1] + (b[1] - a[1]) * s, a[2] + (b[2] - a[2]) * s};
}

// A face's corners as a key independent of vertex numbering, in float as
// MeshLab stores them (a file written by MeshLab from one read in double
// then matches).
using FaceKey = std::array<float, 9>;
FaceKey keyOf(const std::vector<Point3>& P, const Triangle& t) {
  std::array<std::array<float, 3>, 3> c;
  for (int k = 0; k < 3; ++k) c[k] = {float(P[t[k]][0]), float(P[t[k]][1]), float(P[t[k]][2])};
  std::sort(c.begin(), c.end());
  FaceKey key;
  for (int k = 0; k < 9; ++k) key[k] = c[k / 3][k % 3];
  return key;
}

// ---- the picture ------------------------------------------------------------------

struct Options {
  std::vector<std::string> inputs;
  std::string out, colour, before, frame;
  double tau = 0, range_low = NAN, range_high = NAN;
  ClearanceScope scope = ClearanceScope::kBoth;
  bool borders = false;
  double focus[4] = {0, 0, 0, 0};  // centre and radius; radius 0: no close-up
  Point3 view{-1, -0.6, -1.6};     // from the front left, slightly above
  int width = 800, height = 600;
};

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw InvalidInputError(a + " needs a value");
      return argv[++i];
    };
    if (a == "-o") {
      o.out = value();
    } else if (a == "--colour" || a == "--color") {
      o.colour = value();
      static const std::set<std::string> modes = {"plain",     "layers",       "patches",
                                                  "new-faces", "intersecting", "clearance"};
      if (!modes.count(o.colour))
        throw InvalidInputError("unknown --colour " + o.colour +
                                " (plain, layers, patches, intersecting, new-faces, clearance)");
    } else if (a == "--before") {
      o.before = value();
    } else if (a == "--frame") {
      o.frame = value();
    } else if (a == "--tau") {
      o.tau = std::stod(value());
    } else if (a == "--range") {
      if (std::sscanf(value().c_str(), "%lf,%lf", &o.range_low, &o.range_high) != 2)
        throw InvalidInputError("expected --range LOW,HIGH");
    } else if (a == "--scope") {
      const std::string scope = value();
      if (scope == "within")
        o.scope = ClearanceScope::kWithinLayers;
      else if (scope == "between")
        o.scope = ClearanceScope::kBetweenLayers;
      else if (scope == "both")
        o.scope = ClearanceScope::kBoth;
      else
        throw InvalidInputError("unknown --scope " + scope + " (within, between, both)");
    } else if (a == "--focus") {
      if (std::sscanf(value().c_str(), "%lf,%lf,%lf,%lf", &o.focus[0], &o.focus[1], &o.focus[2],
                      &o.focus[3]) != 4 ||
          !(o.focus[3] > 0))
        throw InvalidInputError("expected --focus X,Y,Z,R (R more than 0)");
    } else if (a == "--borders") {
      o.borders = true;
    } else if (a == "--view") {
      o.view = parseTriple(value());
    } else if (a == "--size") {
      if (std::sscanf(value().c_str(), "%d,%d", &o.width, &o.height) != 2 || o.width < 16 ||
          o.height < 16 || o.width > 8000 || o.height > 8000)
        throw InvalidInputError("expected --size W,H (16 to 8000 each)");
    } else if (!a.empty() && a[0] == '-') {
      throw InvalidInputError("unknown option " + a);
    } else {
      o.inputs.push_back(a);
    }
  }
  if (o.inputs.empty() || o.out.empty())
    throw InvalidInputError("usage: meshmend_render [options] INPUT... -o OUT.ppm");
  if (o.colour == "new-faces" && o.before.empty())
    throw InvalidInputError("--colour new-faces needs --before FILE (the mesh before the repair)");
  if (o.colour == "clearance" && !(o.tau > 0))
    throw InvalidInputError("--colour clearance needs --tau T (more than 0, in mesh units)");
  if (!(o.view.Norm() > 0)) throw InvalidInputError("--view must not be 0,0,0");
  return o;
}

// Where the red faces are: the ball around their bounding box (for --focus).
void reportRed(const std::vector<Point3>& P, const std::vector<Triangle>& T,
               const std::vector<char>& red) {
  Point3 lo(HUGE_VAL, HUGE_VAL, HUGE_VAL), hi = lo * -1.0;
  for (std::size_t f = 0; f < T.size(); ++f)
    if (red[f])
      for (int v : T[f])
        for (int k = 0; k < 3; ++k)
          lo[k] = std::min(lo[k], P[v][k]), hi[k] = std::max(hi[k], P[v][k]);
  if (lo[0] > hi[0]) return;
  const Point3 c = (lo + hi) * 0.5;
  std::fprintf(stderr, "meshmend_render: red faces within %.6g,%.6g,%.6g,%.6g (--focus)\n", c[0],
               c[1], c[2], (hi - lo).Norm() / 2);
}

struct Scene {
  std::vector<Point3> P;    // all layers' points
  std::vector<Triangle> T;  // all layers' faces (indices into P)
  std::vector<Colour> faceColour;
  std::vector<int> label;           // faces with different labels are outlined (-1: never)
  std::vector<double> vertexValue;  // clearance per point (empty: flat face colours)
};

Scene colourScene(const std::vector<Layer>& layers, const Options& o) {
  Scene s;
  std::vector<int> layerOf;
  for (std::size_t l = 0; l < layers.size(); ++l) {
    const int base = int(s.P.size());
    s.P.insert(s.P.end(), layers[l].points.begin(), layers[l].points.end());
    for (Triangle t : layers[l].triangles) {
      for (int& v : t) v += base;
      s.T.push_back(t);
      layerOf.push_back(int(l));
    }
  }
  if (s.T.empty()) throw InvalidInputError("the inputs have no faces");
  const std::string mode = o.colour.empty() ? (layers.size() > 1 ? "layers" : "plain") : o.colour;
  s.faceColour.assign(s.T.size(), kPlain);
  s.label.assign(s.T.size(), -1);
  if (mode == "layers") {
    for (std::size_t f = 0; f < s.T.size(); ++f) {
      s.faceColour[f] = rgb(patchColour(layerOf[f] * 3 + 1));
      s.label[f] = layerOf[f];
    }
  } else if (mode == "patches") {
    const Mesh merged = makeMesh(s.P, s.T);
    const Patches patches = paintPatches(merged, {});
    for (std::size_t f = 0; f < s.T.size(); ++f) {
      s.label[f] = patches.patch_of_face[f];
      s.faceColour[f] = rgb(patchColour(s.label[f] + 1));  // patch 0 not red: red marks defects
    }
  } else if (mode == "intersecting") {
    std::vector<Mesh> meshes(layers.size());
    std::vector<const Mesh*> pointers;
    for (std::size_t l = 0; l < layers.size(); ++l) {
      buildMesh(meshes[l], layers[l].points, layers[l].triangles);
      pointers.push_back(&meshes[l]);
    }
    const FindIntersectionsResult r = findIntersections(pointers);
    std::size_t f = 0, red = 0;
    std::vector<char> hits(s.T.size(), 0);
    for (std::size_t l = 0; l < layers.size(); ++l)
      for (std::size_t i = 0; i < layers[l].triangles.size(); ++i, ++f) {
        const bool hit = r.face_involved[l][i];
        s.faceColour[f] = hit ? kRed : kPlain;
        s.label[f] = hit;
        hits[f] = hit;
        red += hit;
      }
    std::fprintf(stderr, "meshmend_render: %zu intersecting pairs, %zu faces in them\n",
                 r.pairs.size(), red);
    reportRed(s.P, s.T, hits);
  } else if (mode == "new-faces") {
    const std::vector<Layer> before = loadInputs({o.before});
    std::set<FaceKey> old;
    for (const Layer& l : before)
      for (const Triangle& t : l.triangles) old.insert(keyOf(l.points, t));
    std::size_t made = 0;
    for (std::size_t f = 0; f < s.T.size(); ++f) {
      const bool isNew = !old.count(keyOf(s.P, s.T[f]));
      s.faceColour[f] = isNew ? kNew : kPlain;
      s.label[f] = isNew;
      made += isNew;
    }
    std::fprintf(stderr, "meshmend_render: %zu of %zu faces are not in %s\n", made, s.T.size(),
                 o.before.c_str());
  } else if (mode == "clearance") {
    std::vector<Mesh> meshes(layers.size());
    std::vector<const Mesh*> pointers;
    for (std::size_t l = 0; l < layers.size(); ++l) {
      buildMesh(meshes[l], layers[l].points, layers[l].triangles);
      pointers.push_back(&meshes[l]);
    }
    const double high = std::isnan(o.range_high) ? 3 * o.tau : o.range_high;
    ClearanceMeasureOptions options;
    options.tau = o.tau;
    options.scope = o.scope;
    options.local_max = std::max(high, o.tau) * 1.01;
    const ClearanceMeasure r = measureClearance(pointers, options);
    for (const auto& values : r.vertex_clearance)
      s.vertexValue.insert(s.vertexValue.end(), values.begin(), values.end());
    std::vector<char> below;
    for (const auto& faces : r.faces_below_tau)
      below.insert(below.end(), faces.begin(), faces.end());
    reportRed(s.P, s.T, below);
    std::fprintf(stderr, "meshmend_render: minimum clearance %.6g, %zu face pairs below %.6g\n",
                 r.found ? r.min_distance : NAN, r.violating_pairs, o.tau);
  }
  return s;
}

// Bounds of the points along the camera axes u, v.
void boundsOf(const std::vector<Point3>& P, const Point3& u, const Point3& v, double lo[2],
              double hi[2]) {
  lo[0] = lo[1] = HUGE_VAL;
  hi[0] = hi[1] = -HUGE_VAL;
  for (const Point3& p : P) {
    lo[0] = std::min(lo[0], p * u), hi[0] = std::max(hi[0], p * u);
    lo[1] = std::min(lo[1], p * v), hi[1] = std::max(hi[1], p * v);
  }
}

void render(const Scene& s, const std::vector<Point3>& framePoints, const Options& o) {
  constexpr int kSamples = 2;  // supersampling per axis
  const int W = o.width * kSamples, H = o.height * kSamples;
  // A camera frame: w along the view direction, u to the right, v up.
  Point3 w = o.view;
  w.Normalize();
  Point3 up(0, 1, 0);
  if (std::fabs(w * up) > 0.99) up = Point3(0, 0, 1);
  Point3 u = up ^ w;
  u.Normalize();
  Point3 v = w ^ u;
  v.Normalize();
  double lo[2], hi[2];
  boundsOf(framePoints, u, v, lo, hi);
  if (o.focus[3] > 0) {
    const Point3 c(o.focus[0], o.focus[1], o.focus[2]);
    lo[0] = c * u - o.focus[3], hi[0] = c * u + o.focus[3];
    lo[1] = c * v - o.focus[3], hi[1] = c * v + o.focus[3];
  }
  const double spanX = std::max(hi[0] - lo[0], 1e-300), spanY = std::max(hi[1] - lo[1], 1e-300);
  const double scale = 0.92 * std::min(W / spanX, H / spanY);
  auto project = [&](const Point3& p) {
    return Point3(W / 2.0 + (p * u - (lo[0] + hi[0]) / 2) * scale,
                  H / 2.0 - (p * v - (lo[1] + hi[1]) / 2) * scale, p * w);
  };
  std::vector<Point3> Q(s.P.size());
  double zlo = HUGE_VAL, zhi = -HUGE_VAL;
  for (std::size_t i = 0; i < s.P.size(); ++i) {
    Q[i] = project(s.P[i]);
    zlo = std::min(zlo, Q[i][2]), zhi = std::max(zhi, Q[i][2]);
  }
  std::vector<float> depth(std::size_t(W) * H, INFINITY);
  std::vector<Colour> image(std::size_t(W) * H, Colour{1, 1, 1});
  Point3 light = w * -1.0 + v * 0.6 + u * -0.3;
  light.Normalize();
  const double rangeLow = std::isnan(o.range_low) ? o.tau : o.range_low;
  const double rangeHigh = std::isnan(o.range_high) ? 3 * o.tau : o.range_high;

  for (std::size_t f = 0; f < s.T.size(); ++f) {
    const Triangle& t = s.T[f];
    const Point3 &a = Q[t[0]], &b = Q[t[1]], &c = Q[t[2]];
    Point3 n = (s.P[t[1]] - s.P[t[0]]) ^ (s.P[t[2]] - s.P[t[0]]);
    if (!(n.Norm() > 0)) continue;
    n.Normalize();
    const double shade = 0.3 + 0.7 * std::fabs(n * light);  // two-sided
    const double area = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
    if (area == 0) continue;
    const int x0 = std::max(0, int(std::floor(std::min({a[0], b[0], c[0]}))));
    const int x1 = std::min(W - 1, int(std::ceil(std::max({a[0], b[0], c[0]}))));
    const int y0 = std::max(0, int(std::floor(std::min({a[1], b[1], c[1]}))));
    const int y1 = std::min(H - 1, int(std::ceil(std::max({a[1], b[1], c[1]}))));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const double px = x + 0.5, py = y + 0.5;
        const double l0 = ((b[0] - px) * (c[1] - py) - (c[0] - px) * (b[1] - py)) / area;
        const double l1 = ((c[0] - px) * (a[1] - py) - (a[0] - px) * (c[1] - py)) / area;
        const double l2 = 1 - l0 - l1;
        if (l0 < 0 || l1 < 0 || l2 < 0) continue;
        const float z = float(l0 * a[2] + l1 * b[2] + l2 * c[2]);
        const std::size_t i = std::size_t(y) * W + x;
        if (z >= depth[i]) continue;
        depth[i] = z;
        Colour base = s.faceColour[f];
        if (!s.vertexValue.empty()) {
          const double d =
              l0 * s.vertexValue[t[0]] + l1 * s.vertexValue[t[1]] + l2 * s.vertexValue[t[2]];
          base = d < o.tau
                     ? kRed
                     : ramp(rangeHigh > rangeLow
                                ? std::clamp((d - rangeLow) / (rangeHigh - rangeLow), 0.0, 1.0)
                                : 1.0);
        }
        for (int k = 0; k < 3; ++k) image[i][k] = base[k] * shade;
      }
  }

  // Lines: edges between faces of different labels (dark), borders (red).
  std::map<std::pair<int, int>, std::vector<int>> edgeFaces;
  const bool outlines = std::any_of(s.label.begin(), s.label.end(), [](int l) { return l != -1; });
  if (outlines || o.borders)
    for (std::size_t f = 0; f < s.T.size(); ++f)
      for (int k = 0; k < 3; ++k) {
        const int a = s.T[f][k], b = s.T[f][(k + 1) % 3];
        edgeFaces[{std::min(a, b), std::max(a, b)}].push_back(int(f));
      }
  const float bias = float(0.004 * (zhi - zlo));
  auto stamp = [&](const Point3& a, const Point3& b, double radius, const Colour* colour) {
    const double length = std::hypot(b[0] - a[0], b[1] - a[1]);
    const int steps = std::max(1, int(std::ceil(length / 0.5)));
    const int r = int(std::ceil(radius));
    for (int i = 0; i <= steps; ++i) {
      const double t = double(i) / steps;
      const double px = a[0] + (b[0] - a[0]) * t, py = a[1] + (b[1] - a[1]) * t;
      const float z = float(a[2] + (b[2] - a[2]) * t);
      for (int dy = -r; dy <= r; ++dy)
        for (int dx = -r; dx <= r; ++dx) {
          const int x = int(std::floor(px)) + dx, y = int(std::floor(py)) + dy;
          if (x < 0 || y < 0 || x >= W || y >= H) continue;
          if (std::hypot(x + 0.5 - px, y + 0.5 - py) > radius) continue;
          const std::size_t p = std::size_t(y) * W + x;
          if (z > depth[p] + bias) continue;  // hidden behind the surface
          if (colour) {
            image[p] = *colour;
          } else {
            for (double& channel : image[p]) channel *= 0.3;
            depth[p] = -INFINITY;  // darken once
          }
        }
    }
  };
  for (const auto& [edge, faces] : edgeFaces) {
    bool mixed = false;
    for (int f : faces) mixed |= s.label[f] != s.label[faces[0]];
    if (mixed) stamp(Q[edge.first], Q[edge.second], 1.3, nullptr);
  }
  if (o.borders)
    for (const auto& [edge, faces] : edgeFaces)
      if (faces.size() == 1) stamp(Q[edge.first], Q[edge.second], 2.2, &kRed);

  // Down-sample (box filter) and write.
  std::ofstream out(o.out, std::ios::binary);
  out << "P6\n" << o.width << " " << o.height << "\n255\n";
  std::vector<unsigned char> row(std::size_t(o.width) * 3);
  for (int y = 0; y < o.height; ++y) {
    for (int x = 0; x < o.width; ++x)
      for (int k = 0; k < 3; ++k) {
        double sum = 0;
        for (int sy = 0; sy < kSamples; ++sy)
          for (int sx = 0; sx < kSamples; ++sx)
            sum += image[std::size_t(y * kSamples + sy) * W + x * kSamples + sx][k];
        row[3 * x + k] =
            (unsigned char)std::lround(std::clamp(sum / (kSamples * kSamples), 0.0, 1.0) * 255);
      }
    out.write(reinterpret_cast<const char*>(row.data()), std::streamsize(row.size()));
  }
  if (!out) throw InvalidInputError("cannot write " + o.out);
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Options o = parse(argc, argv);
    const std::vector<Layer> layers = loadInputs(o.inputs);
    const Scene scene = colourScene(layers, o);
    std::vector<Point3> framePoints = scene.P;
    if (!o.frame.empty()) {
      framePoints.clear();
      for (const Layer& l : loadInputs({o.frame}))
        framePoints.insert(framePoints.end(), l.points.begin(), l.points.end());
    }
    render(scene, framePoints, o);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "meshmend_render: %s\n", e.what());
    return 2;
  }
}
