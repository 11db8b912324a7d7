#include "common/io/obj_reader.h"

#include <cstdio>
#include <fstream>

#include <gtest/gtest.h>

#include "common/base/errors.h"

namespace meshmend {
namespace {

std::string writeTemp(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "/" + name;
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

TEST(ObjReader, ReadsPositionsTexcoordsNormalsAndPolygons) {
  const std::string path =
      writeTemp("quad.obj",
                "# a quad\r\nmtllib quad.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\n"
                "usemtl red\nf 1/1/1 2/2/1 3/3/1 4/4/1\n");
  writeTemp("quad.mtl", "newmtl red\nKd 1 0 0\nmap_Kd -s 1 1 1 tex.png\n");
  const ObjData d = readObj(path);
  ASSERT_EQ(d.positions.size(), 4u);
  ASSERT_EQ(d.polygons.size(), 1u);
  ASSERT_EQ(d.polygons[0].size(), 4u);
  EXPECT_EQ(d.polygons[0][2].vertex, 2);
  EXPECT_EQ(d.polygons[0][2].texcoord, 2);
  EXPECT_EQ(d.polygons[0][2].normal, 0);
  ASSERT_EQ(d.materials.size(), 1u);
  EXPECT_EQ(d.materials[0].diffuse[0], 1.f);
  EXPECT_EQ(d.materials[0].diffuse_texture, "tex.png");
  EXPECT_EQ(d.polygon_material[0], 0);
  EXPECT_TRUE(d.warnings.empty());
}

TEST(ObjReader, NegativeIndicesAndVertexColours) {
  const ObjData d = readObj(writeTemp("neg.obj",
                                      "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\n"
                                      "f -3 -2 -1\nf 1//1 2//1 3//1\nvn 0 0 1\n"));
  EXPECT_EQ(d.polygons[0][0].vertex, 0);
  EXPECT_EQ(d.polygons[0][2].vertex, 2);
  EXPECT_EQ(d.polygons[1][1].normal, 0);
  ASSERT_EQ(d.vertex_colors.size(), 3u);
  EXPECT_EQ(d.vertex_colors[1][1], 1.f);
}

TEST(ObjReader, ContinuationLinesAndUnsupportedStatements) {
  const ObjData d = readObj(
      writeTemp("cont.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 \\\n 2 3\ncurv 0 1 1 2\nl 1 2\n"));
  ASSERT_EQ(d.polygons.size(), 1u);
  EXPECT_EQ(d.polygons[0].size(), 3u);
  ASSERT_EQ(d.warnings.size(), 1u);
  EXPECT_NE(d.warnings[0].find("2 lines"), std::string::npos) << d.warnings[0];
}

TEST(ObjReader, MissingMaterialLibraryIsAWarning) {
  const ObjData d = readObj(writeTemp("nomtl.obj",
                                      "mtllib nowhere.mtl\nv 0 0 0\nv 1 0 0\n"
                                      "v 0 1 0\nusemtl x\nf 1 2 3\n"));
  ASSERT_EQ(d.warnings.size(), 1u);
  EXPECT_NE(d.warnings[0].find("nowhere.mtl"), std::string::npos);
  EXPECT_EQ(d.polygon_material[0], 0);
}

TEST(ObjReader, MaterialLibraryThatIsNotARegularFileIsIgnored) {
  // A device or a folder named as material library (names are relative to
  // the file's folder): reading /dev/zero line by line would never end. It
  // is a warning, like a missing one.
  const ObjData d = readObj(writeTemp(
      "devmtl.obj",
      "mtllib ../../../../../../../../dev/zero\nmtllib .\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"));
  ASSERT_EQ(d.warnings.size(), 2u);
  EXPECT_NE(d.warnings[0].find("not found"), std::string::npos);
  EXPECT_EQ(d.polygons.size(), 1u);
}

TEST(ObjReader, ErrorsNameFileAndLine) {
  auto message = [](const std::string& text) {
    try {
      readObj(writeTemp("bad.obj", text));
    } catch (const InvalidInputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("v 0 0 0\nv 1 nan 0\n").find("line 2: non-finite"), std::string::npos);
  EXPECT_NE(message("v 0 0 x\n").find("line 1: 'x' is not a number"), std::string::npos);
  EXPECT_NE(message("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n").find("refers to vertex 9"),
            std::string::npos);
  EXPECT_NE(message("v 0 0 0\nf 0 1 2\n").find("index 0"), std::string::npos);
  EXPECT_NE(message("# nothing\n").find("defines no vertex"), std::string::npos);
  // Beyond int an index would wrap to a valid-looking or negative one.
  EXPECT_NE(message("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4294967298\n").find("out of range"),
            std::string::npos);
  EXPECT_NE(message("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -9999999999\n").find("out of range"),
            std::string::npos);
  EXPECT_THROW(readObj("/nonexistent/file.obj"), InvalidInputError);
}

}  // namespace
}  // namespace meshmend
