#include "common/render/render_channels.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <tuple>

#include "common/base/errors.h"

namespace meshmend {

namespace {

// Corner k's own barycentric part of (u, v): corners 0, 1, 2 sit at (1, 0),
// (0, 1) and (0, 0).
constexpr float kCornerU[3] = {1, 0, 0};
constexpr float kCornerV[3] = {0, 1, 0};

float storedValue(double value) {
  if (!std::isfinite(value) || std::fabs(value) > kLargestValue)
    return value < 0 ? -kLargestValue : kLargestValue;
  return float(value);
}

}  // namespace

std::vector<WedgeCoords> encodeVertexValues(const Triangles& faces,
                                            const std::vector<double>& values) {
  const float tag = float(RenderChannel::kClearance);
  std::vector<WedgeCoords> out(faces.size());
  for (std::size_t f = 0; f < faces.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int v = faces[f][k];
      if (v < 0 || std::size_t(v) >= values.size())
        throw InvalidInputError("face " + std::to_string(f) + " uses vertex " + std::to_string(v) +
                                ", which has no value (" + std::to_string(values.size()) +
                                " values)");
      out[f][k] = {storedValue(values[v]), tag};
    }
  return out;
}

std::vector<WedgeCoords> encodeFaceLabels(const Triangles& faces, const std::vector<int>& labels,
                                          RenderChannel channel, bool borders_are_boundaries) {
  if (labels.size() != faces.size())
    throw InvalidInputError(std::to_string(labels.size()) + " labels for " +
                            std::to_string(faces.size()) + " faces");
  for (std::size_t f = 0; f < labels.size(); ++f)
    if (labels[f] < 0)
      throw InvalidInputError("face " + std::to_string(f) + " has the negative label " +
                              std::to_string(labels[f]));

  // Edges as (smaller vertex, larger vertex, face, corner), grouped by edge.
  std::vector<std::tuple<int, int, int, int>> edges;
  edges.reserve(faces.size() * 3);
  for (std::size_t f = 0; f < faces.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = faces[f][k], b = faces[f][(k + 1) % 3];
      edges.emplace_back(std::min(a, b), std::max(a, b), int(f), k);
    }
  std::sort(edges.begin(), edges.end());
  std::vector<int> mask(faces.size(), 0);
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    bool mixed = false;
    while (j < edges.size() && std::get<0>(edges[j]) == std::get<0>(edges[i]) &&
           std::get<1>(edges[j]) == std::get<1>(edges[i])) {
      mixed |= labels[std::get<2>(edges[j])] != labels[std::get<2>(edges[i])];
      ++j;
    }
    if (mixed || (j - i == 1 && borders_are_boundaries))
      for (std::size_t e = i; e < j; ++e) mask[std::get<2>(edges[e])] |= 1 << std::get<3>(edges[e]);
    i = j;
  }

  const float tag = float(channel);
  std::vector<WedgeCoords> out(faces.size());
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const float label = float(labels[f] % kLabelModulus);
    for (int k = 0; k < 3; ++k)
      out[f][k] = {4 * label + kCornerU[k], tag + 4 * float(mask[f]) + kCornerV[k]};
  }
  return out;
}

DecodedChannel decodeChannel(float u, float v) {
  DecodedChannel d;
  const float tag = std::floor(v / 100 + 0.5f) * 100;
  if (tag == float(RenderChannel::kClearance)) {
    d.channel = RenderChannel::kClearance;
    d.value = u;
  } else if (tag == float(RenderChannel::kPatches) || tag == float(RenderChannel::kFaceChanges)) {
    d.channel = RenderChannel(int(tag));
    const float rest = v - tag;
    const float mask = std::floor(rest / 4 + 0.375f), label = std::floor(u / 4 + 0.375f);
    d.boundary_mask = int(mask);
    d.label = int(label);
    const float b0 = u - 4 * label, b1 = rest - 4 * mask;
    d.barycentric = {b0, b1, 1 - b0 - b1};
  }
  return d;
}

}  // namespace meshmend
