// OBJ faces of any size: ear clipping of convex, concave, self-intersecting and degenerate faces, and quads split
// exactly as tinyobjloader split them before (so meshes, and the golden images, keep their triangles).
#include <gtest/gtest.h>

#include <tiny_obj_loader.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "mesh/triangulate.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/mesh/mesh.hpp"
#include "support/test_support.hpp"

namespace qdmr {
namespace {

using mesh_detail::triangulate_polygon;

// A planar face in 3D: the 2D outline (x, y) on a tilted plane, so no axis plane is the face's plane.
std::vector<glm::dvec3> on_tilted_plane(const std::vector<glm::dvec2>& outline) {
  const glm::dvec3 origin(0.3, -0.2, 1.0), u = glm::normalize(glm::dvec3(1, 0.5, 0.25)),
                   v = glm::normalize(glm::cross(glm::dvec3(0.2, 0.1, 1), u));
  std::vector<glm::dvec3> face;
  for (const glm::dvec2& p : outline) face.push_back(origin + p.x * u + p.y * v);
  return face;
}

double shoelace(const std::vector<glm::dvec2>& outline) {
  double twice = 0;
  for (std::size_t i = 0; i < outline.size(); ++i) {
    const glm::dvec2 a = outline[i], b = outline[(i + 1) % outline.size()];
    twice += a.x * b.y - a.y * b.x;
  }
  return twice / 2;
}

double signed_area(glm::dvec2 a, glm::dvec2 b, glm::dvec2 c) {
  return ((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x)) / 2;
}

// A triangulation of a simple counter-clockwise outline: n - 2 triangles, none clockwise, their areas adding up
// to the outline's, and no corner of the outline strictly inside any of them. A triangle of three collinear
// corners (area 0: the comb's tooth tops lie on one line) is allowed: the face's plane is found in floating point,
// where such a corner can come out convex by an ulp; the rasterizer culls it.
void expect_triangulates(const std::vector<glm::dvec2>& outline) {
  const auto result = triangulate_polygon(on_tilted_plane(outline), "test");
  ASSERT_FALSE(result.degenerate);
  ASSERT_EQ(result.corners.size(), 3 * (outline.size() - 2));
  double total = 0;
  for (std::size_t t = 0; t < result.corners.size(); t += 3) {
    const glm::dvec2 a = outline[result.corners[t]], b = outline[result.corners[t + 1]], c = outline[result.corners[t + 2]];
    const double area = signed_area(a, b, c);
    ASSERT_GE(area, 0) << "triangle " << t / 3;
    total += area;
    for (const glm::dvec2& p : outline) {
      if (p == a || p == b || p == c) continue;
      const bool inside = signed_area(a, b, p) > 0 && signed_area(b, c, p) > 0 && signed_area(c, a, p) > 0;
      ASSERT_FALSE(inside) << "triangle " << t / 3 << " holds (" << p.x << ", " << p.y << ")";
    }
  }
  // Each triangle's area is exact to a few ulp of the outline's size (coordinates of order 1): 1e-9 relative
  // leaves a wide margin over 1000 triangles, and a missing or doubled triangle is off by 1e-3 or more.
  EXPECT_NEAR(total, shoelace(outline), 1e-9 * std::abs(shoelace(outline)));
}

// The mesh qdmr loads from an OBJ file of this text.
MeshData obj_mesh(const std::filesystem::path& file, const std::string& text) {
  test::write_file(file, text);
  MeshDesc desc;
  desc.kind = MeshKind::Obj;
  desc.file = file;
  return build_mesh(desc, "test");
}

TEST(Triangulate, ConvexThousandGon) {
  std::vector<glm::dvec2> circle;
  for (int i = 0; i < 1000; ++i) {
    const double a = 2 * std::numbers::pi * i / 1000;
    circle.emplace_back(std::cos(a), std::sin(a));
  }
  expect_triangulates(circle);
}

TEST(Triangulate, ConcaveHundredGonStar) {
  std::vector<glm::dvec2> star;
  for (int i = 0; i < 100; ++i) {
    const double a = 2 * std::numbers::pi * i / 100, r = i % 2 ? 0.35 : 1.0;
    star.emplace_back(r * std::cos(a), r * std::sin(a));
  }
  expect_triangulates(star);
}

TEST(Triangulate, ConcaveCombAndClockwiseOutlines) {
  // A comb: ten teeth on a bar (42 corners), most ears blocked by the next tooth's corners. Counter-clockwise:
  // along the bar, then up and down each tooth from the right.
  std::vector<glm::dvec2> comb{{0, 0}, {20, 0}};
  for (int k = 0; k < 10; ++k) {
    const double right = 20 - 2 * k, left = right - 1;
    comb.insert(comb.end(), {{right, 5}, {left, 5}, {left, 1}, {left - 1, 1}});
  }
  expect_triangulates(comb);
  // The same outline clockwise: the face's normal flips with it, the triangles keep its winding.
  std::vector<glm::dvec2> reversed(comb.rbegin(), comb.rend());
  const auto result = triangulate_polygon(on_tilted_plane(reversed), "test");
  ASSERT_EQ(result.corners.size(), 3 * (reversed.size() - 2));
  for (std::size_t t = 0; t < result.corners.size(); t += 3)
    EXPECT_LE(signed_area(reversed[result.corners[t]], reversed[result.corners[t + 1]], reversed[result.corners[t + 2]]), 0);
}

TEST(Triangulate, SelfIntersectingFaceStillGivesEveryCorner) {
  // A pentagram (each corner joined to the second next) and a bow tie: no triangulation exists; n - 2
  // triangles of the face's own corners come out, without a hang.
  std::vector<glm::dvec2> pentagram, bow_tie{{0, 0}, {1, 1}, {1, 0}, {0, 1}};
  for (int i = 0; i < 5; ++i) {
    const double a = 2 * std::numbers::pi * (2 * i % 5) / 5;
    pentagram.emplace_back(std::cos(a), std::sin(a));
  }
  for (const auto& outline : {pentagram, bow_tie}) {
    const auto result = triangulate_polygon(on_tilted_plane(outline), "test");
    if (result.degenerate) continue;  // the bow tie's halves cancel: no area, dropped
    ASSERT_EQ(result.corners.size(), 3 * (outline.size() - 2));
    for (std::uint32_t c : result.corners) EXPECT_LT(c, outline.size());
  }
}

TEST(Triangulate, CollinearAndCoincidentFacesAreDegenerate) {
  std::vector<glm::dvec2> line, point(7, glm::dvec2(0.5, 0.5));
  for (int i = 0; i < 6; ++i) line.emplace_back(i, 2 * i);
  line.emplace_back(2.5, 5);  // back along the same line
  EXPECT_TRUE(triangulate_polygon(on_tilted_plane(line), "test").degenerate);
  EXPECT_TRUE(triangulate_polygon(on_tilted_plane(point), "test").degenerate);
}

// Quads: the loader's split equals tinyobjloader's own (triangulate = true), which split every OBJ quad before.
TEST(Triangulate, QuadsAreSplitAsTinyobjloaderSplitThem) {
  std::mt19937 random(57);
  std::uniform_real_distribution<float> coordinate(-1, 1);
  std::ostringstream text;
  const int quads = 500;
  for (int q = 0; q < quads; ++q) {
    // Near-squares with jittered corners: both diagonals win about equally often.
    const float x = float(q % 25), y = float(q / 25);
    const float corners[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (const auto& c : corners)
      text << "v " << x + c[0] + 0.3f * coordinate(random) << " " << y + c[1] + 0.3f * coordinate(random) << " "
           << 0.2f * coordinate(random) << "\n";
    text << "f " << 4 * q + 1 << " " << 4 * q + 2 << " " << 4 * q + 3 << " " << 4 * q + 4 << "\n";
  }
  test::TempDir dir;
  const MeshData mesh = obj_mesh(dir / "quads.obj", text.str());

  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> materials;
  std::string warn, err;
  std::istringstream in(text.str());
  ASSERT_TRUE(tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, &in, nullptr, true, false)) << err;
  ASSERT_EQ(shapes.size(), 1u);
  const auto& indices = shapes[0].mesh.indices;
  ASSERT_EQ(mesh.indices.size(), indices.size());
  for (std::size_t k = 0; k < indices.size(); ++k) {
    const float* p = &attrib.vertices[3 * std::size_t(indices[k].vertex_index)];
    EXPECT_EQ(mesh.positions[mesh.indices[k]], glm::vec3(p[0], p[1], p[2])) << "corner " << k;
  }
}

TEST(Triangulate, ObjFacesOfAnySizeAndTheDegenerateCount) {
  std::ostringstream text;
  for (int i = 0; i < 1000; ++i) {
    const double a = 2 * std::numbers::pi * i / 1000;
    text << "v " << std::cos(a) << " " << std::sin(a) << " 0\n";
  }
  for (int i = 0; i < 5; ++i) text << "v " << i << " " << i << " 1\n";  // collinear
  text << "f";
  for (int i = 1; i <= 1000; ++i) text << " " << i;
  text << "\nf 1001 1002 1003 1004 1005\n";
  test::TempDir dir;
  const MeshData mesh = obj_mesh(dir / "n.obj", text.str());
  EXPECT_EQ(mesh.triangle_count(), 998u);
  EXPECT_EQ(mesh.degenerate_faces, 1u);
  // Only the degenerate face: nothing to draw, said so.
  try {
    obj_mesh(dir / "line.obj", "v 0 0 0\nv 1 1 1\nv 2 2 2\nv 3 3 3\nf 1 2 3 4\n");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("is degenerate (no area)"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace qdmr
