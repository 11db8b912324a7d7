#include "fuzz/fuzz_input.h"

namespace meshmend::fuzz {

void objReader(const std::uint8_t*, std::size_t);
void meshValidation(const std::uint8_t*, std::size_t);
void triangleIntersection(const std::uint8_t*, std::size_t);
void retriangulateTriangle(const std::uint8_t*, std::size_t);
void split(const std::uint8_t*, std::size_t);
void booleans(const std::uint8_t*, std::size_t);
void removeSelfIntersectionsBody(const std::uint8_t*, std::size_t);
void fillHolesBody(const std::uint8_t*, std::size_t);
void trimAndStitchBody(const std::uint8_t*, std::size_t);
void closeGapsBody(const std::uint8_t*, std::size_t);
void clearanceBody(const std::uint8_t*, std::size_t);

const std::vector<Target>& targets() {
  static const std::vector<Target> all{
      {"obj_reader", objReader},
      {"mesh_validation", meshValidation},
      {"triangle_intersection", triangleIntersection},
      {"retriangulate", retriangulateTriangle},
      {"split", split},
      {"booleans", booleans},
      {"remove_self_intersections", removeSelfIntersectionsBody},
      {"fill_holes", fillHolesBody},
      {"trim_stitch", trimAndStitchBody},
      {"close_gaps", closeGapsBody},
      {"clearance", clearanceBody},
  };
  return all;
}

}  // namespace meshmend::fuzz
