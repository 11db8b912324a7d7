#include "common/render/render_channels.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "common/base/errors.h"

using namespace meshmend;

namespace {

// A fragment's (u, v) as the graphics card interpolates it: in float, at
// barycentric coordinates (w0, w1, w2) of the face's corners.
std::array<float, 2> interpolate(const WedgeCoords& c, float w0, float w1, float w2) {
  return {w0 * c[0][0] + w1 * c[1][0] + w2 * c[2][0], w0 * c[0][1] + w1 * c[1][1] + w2 * c[2][1]};
}

// A strip of four triangles over a 3 x 2 grid of vertices:
//   3---4---5
//   | / | / |
//   0---1---2
const Triangles kStrip = {{0, 1, 4}, {0, 4, 3}, {1, 2, 5}, {1, 5, 4}};

}  // namespace

TEST(RenderChannels, BoundariesAreTheEdgesBetweenDifferentLabels) {
  // Faces 0, 1 form label 7, faces 2, 3 label 9: the shared edge is 1-4.
  const auto coords = encodeFaceLabels(kStrip, {7, 7, 9, 9}, RenderChannel::kPatches, false);
  const int expected[4] = {1 << 1,   // face 0: edge 1-4 from corner 1 to corner 2
                           0,        // face 1 touches label 9 only at a vertex
                           0,        // face 2: its edges are borders or inside label 9
                           1 << 2};  // face 3: edge 4-1 from corner 2 to corner 0
  for (int f = 0; f < 4; ++f) {
    const DecodedChannel d = decodeChannel(coords[f][0][0], coords[f][0][1]);
    EXPECT_EQ(d.channel, RenderChannel::kPatches);
    EXPECT_EQ(d.label, f < 2 ? 7 : 9);
    EXPECT_EQ(d.boundary_mask, expected[f]) << "face " << f;
  }
}

TEST(RenderChannels, BordersCountWhenAsked) {
  const auto coords = encodeFaceLabels(kStrip, {0, 0, 0, 0}, RenderChannel::kFaceChanges, true);
  // Border edges: 0-1, 1-2, 2-5, 5-4, 4-3, 3-0; the inner ones 0-4, 1-4, 1-5 are not.
  const int expected[4] = {1 << 0, (1 << 1) | (1 << 2), (1 << 0) | (1 << 1), 1 << 1};
  for (int f = 0; f < 4; ++f)
    EXPECT_EQ(decodeChannel(coords[f][2][0], coords[f][2][1]).boundary_mask, expected[f]);
  const auto none = encodeFaceLabels(kStrip, {0, 0, 0, 0}, RenderChannel::kFaceChanges, false);
  for (int f = 0; f < 4; ++f)
    EXPECT_EQ(decodeChannel(none[f][1][0], none[f][1][1]).boundary_mask, 0);
}

TEST(RenderChannels, NonManifoldEdgeIsABoundaryWhenItsFacesDiffer) {
  // Three faces on edge 0-1; one of them has another label.
  const Triangles fan = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  const auto coords = encodeFaceLabels(fan, {1, 1, 2}, RenderChannel::kPatches, false);
  EXPECT_EQ(decodeChannel(coords[0][0][0], coords[0][0][1]).boundary_mask, 1 << 0);
  EXPECT_EQ(decodeChannel(coords[1][0][0], coords[1][0][1]).boundary_mask, 1 << 0);
  EXPECT_EQ(decodeChannel(coords[2][0][0], coords[2][0][1]).boundary_mask, 1 << 0);
  const auto same = encodeFaceLabels(fan, {1, 1, 1}, RenderChannel::kPatches, false);
  EXPECT_EQ(decodeChannel(same[0][0][0], same[0][0][1]).boundary_mask, 0);
}

TEST(RenderChannels, InterpolatedCoordinatesDecodeToLabelMaskAndPosition) {
  std::mt19937 random(11);
  std::uniform_real_distribution<float> unit(0, 1);
  for (int label : {0, 1, 2, 37, 1000, kLabelModulus - 1}) {
    // Edges 0 and 2 are borders; give the face a neighbour over edge 1 with another label.
    const Triangles two = {{0, 1, 2}, {2, 1, 3}};
    const auto coords = encodeFaceLabels(two, {label, label + 1}, RenderChannel::kPatches, true);
    for (int sample = 0; sample < 200; ++sample) {
      float w0 = unit(random), w1 = unit(random);
      if (w0 + w1 > 1) w0 = 1 - w0, w1 = 1 - w1;
      const float w2 = 1 - w0 - w1;
      const auto uv = interpolate(coords[0], w0, w1, w2);
      const DecodedChannel d = decodeChannel(uv[0], uv[1]);
      ASSERT_EQ(d.channel, RenderChannel::kPatches);
      ASSERT_EQ(d.label, label);
      ASSERT_EQ(d.boundary_mask, 0b111);
      EXPECT_NEAR(d.barycentric[0], w0, 2e-3) << "label " << label;
      EXPECT_NEAR(d.barycentric[1], w1, 2e-3);
      EXPECT_NEAR(d.barycentric[2], w2, 2e-3);
    }
  }
}

TEST(RenderChannels, LabelsWrapForColourOnly) {
  const Triangles two = {{0, 1, 2}, {2, 1, 3}};
  // kLabelModulus and 0 wrap to the same colour label but still differ: boundary kept.
  const auto coords = encodeFaceLabels(two, {kLabelModulus, 0}, RenderChannel::kPatches, false);
  const DecodedChannel a = decodeChannel(coords[0][0][0], coords[0][0][1]);
  const DecodedChannel b = decodeChannel(coords[1][0][0], coords[1][0][1]);
  EXPECT_EQ(a.label, 0);
  EXPECT_EQ(b.label, 0);
  EXPECT_EQ(a.boundary_mask, 1 << 1);
  EXPECT_EQ(b.boundary_mask, 1 << 0);
}

TEST(RenderChannels, VertexValuesOnEveryCorner) {
  const std::vector<double> values = {0.5,   0.25, 3, std::numeric_limits<double>::infinity(),
                                      -1e40, 0};
  const auto coords = encodeVertexValues(kStrip, values);
  for (std::size_t f = 0; f < kStrip.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int v = kStrip[f][k];
      const DecodedChannel d = decodeChannel(coords[f][k][0], coords[f][k][1]);
      EXPECT_EQ(d.channel, RenderChannel::kClearance);
      const float expected = v == 3 ? kLargestValue : v == 4 ? -kLargestValue : float(values[v]);
      EXPECT_EQ(d.value, expected) << "vertex " << v;
    }
  // Interpolation between a stored infinity stand-in and a small value stays finite.
  const auto uv = interpolate(coords[1], 0.25f, 0.5f, 0.25f);
  EXPECT_TRUE(std::isfinite(uv[0]));
}

TEST(RenderChannels, NoValuesDecodeAsNone) {
  // A mesh without texture coordinates reaches the shader as (0, 0).
  EXPECT_EQ(decodeChannel(0, 0).channel, RenderChannel::kNone);
  // Ordinary texture coordinates (within [0, 1]) are not mistaken for values.
  EXPECT_EQ(decodeChannel(0.3f, 0.9f).channel, RenderChannel::kNone);
}

TEST(RenderChannels, BadInputIsRefused) {
  EXPECT_THROW(encodeFaceLabels(kStrip, {0, 1}, RenderChannel::kPatches, false), InvalidInputError);
  EXPECT_THROW(encodeFaceLabels(kStrip, {0, -1, 0, 0}, RenderChannel::kPatches, false),
               InvalidInputError);
  EXPECT_THROW(encodeVertexValues(kStrip, {1, 2, 3}), InvalidInputError);
}
