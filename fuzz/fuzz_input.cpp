#include "fuzz/fuzz_input.h"

#include <cmath>
#include <cstring>

namespace meshmend::fuzz {

float Input::rawFloat() {
  std::uint8_t b[4];
  for (std::uint8_t& x : b) x = byte();
  float v;
  std::memcpy(&v, b, sizeof v);
  return v;
}

double Input::rawDouble() {
  std::uint8_t b[8];
  for (std::uint8_t& x : b) x = byte();
  double v;
  std::memcpy(&v, b, sizeof v);
  return v;
}

double gridScale(std::uint8_t exponent) {
  return std::ldexp(1.0, int(exponent) - 128);
}

Point3 decodePoint(Input& in, std::uint8_t kind, double scale) {
  Point3 p;
  for (int k = 0; k < 3; ++k) {
    switch (kind & 3) {
      case 1:
        p[k] = double(in.rawFloat());
        break;
      case 2:
        p[k] = in.rawDouble();
        break;
      default:
        p[k] = double(std::int8_t(in.byte())) * scale;
    }
  }
  return p;
}

DecodedMesh decodeMesh(Input& in, std::size_t maxVertices, std::size_t maxFaces) {
  DecodedMesh m;
  m.flags = in.byte();
  const std::uint8_t kind = in.byte();
  const double scale = gridScale(in.byte());
  const std::size_t n = std::min<std::size_t>(in.u16(), maxVertices);
  for (std::size_t i = 0; i < n && in.left() > 0; ++i)
    m.points.push_back(decodePoint(in, kind, scale));
  if (m.points.empty()) return m;
  const auto nv = std::uint32_t(m.points.size());
  while (in.left() >= 6 && m.triangles.size() < maxFaces) {
    Triangle t;
    for (int& v : t) v = int(in.u16() % nv);
    m.triangles.push_back(t);
  }
  return m;
}

}  // namespace meshmend::fuzz
