// What the fuzz targets share: a reader over libFuzzer's bytes, small meshes
// decoded from them, and the finding a target reports when a property of
// its entry point does not hold.
//
// A mesh is encoded as
//   flags (1 byte: the target's options), coordinate kind (1 byte),
//   scale exponent (1 byte), vertex count (2 bytes), the coordinates, then
//   faces as three 2-byte vertex numbers (taken modulo the vertex count)
//   until the bytes run out.
// Coordinate kinds: 0 (and 3) a grid, one signed byte per coordinate times
// 2^(exponent - 128), which makes coincident points, coplanar faces and
// T-junctions common and covers 1e-38 to 1.7e38; 1 raw floats; 2 raw
// doubles (NaN, infinities and any magnitude). fuzz/seed_corpus.py writes
// real meshes in this form.
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/base/mesh.h"

namespace meshmend::fuzz {

// A property of the code under test that does not hold: the fuzz driver
// aborts on it (a finding), the regression test fails.
class Finding : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

// Throws Finding with `what` unless `condition`.
inline void check(bool condition, const std::string& what) {
  if (!condition) throw Finding(what);
}

// Reads fixed-size values from the input; past its end every value is 0.
class Input {
 public:
  Input(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  std::uint8_t byte() { return pos_ < size_ ? data_[pos_++] : 0; }
  std::uint16_t u16() {
    const std::uint16_t lo = byte();
    return std::uint16_t(lo | (std::uint16_t(byte()) << 8));
  }
  float rawFloat();
  double rawDouble();
  std::size_t left() const { return size_ - pos_; }
  // The rest of the input.
  const std::uint8_t* rest() const { return data_ + pos_; }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

struct DecodedMesh {
  std::uint8_t flags = 0;  // the encoding's first byte, for the target's options
  std::vector<Point3> points;
  std::vector<Triangle> triangles;
};

// Decodes one mesh (see the top of this file). At most `maxVertices`
// vertices and `maxFaces` faces (the rest of a longer input is left for
// the caller); a mesh without vertices has no faces.
DecodedMesh decodeMesh(Input& in, std::size_t maxVertices, std::size_t maxFaces);

// One point in the encoding's coordinate kind and scale (for targets that
// decode loose points, not meshes).
Point3 decodePoint(Input& in, std::uint8_t kind, double scale);
double gridScale(std::uint8_t exponent);

// The number of the targets' bodies, by name (fuzz/targets.cpp).
using Body = void (*)(const std::uint8_t* data, std::size_t size);
struct Target {
  const char* name;
  Body body;
};
const std::vector<Target>& targets();

}  // namespace meshmend::fuzz
