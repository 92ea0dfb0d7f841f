#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <cmath>
#include <string>

#include <glm/geometric.hpp>

#include "qdmr/core/error.hpp"
#include "qdmr/mesh/mesh.hpp"
#include "support/test_support.hpp"

namespace qdmr {
namespace {

const std::string kWhere = "scene.json: /objects/0/mesh";

// Frames are computed in double and rounded to float (relative error 2^-24 per component) or normalised in
// float by compute_tangents (a few ulp): unit length and orthogonality hold to ~1e-6. 1e-5 leaves margin
// while any wrong frame is off by O(1).
constexpr float kFrameTolerance = 1e-5f;

bool finite(glm::vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

void expect_consistent(const MeshData& m) {
  const std::size_t n = m.vertex_count();
  ASSERT_GT(n, 0u);
  ASSERT_EQ(m.normals.size(), n);
  ASSERT_EQ(m.tangents.size(), n);
  ASSERT_EQ(m.uvs.size(), n);
  ASSERT_EQ(m.indices.size() % 3, 0u);
  for (const std::uint32_t i : m.indices) ASSERT_LT(i, n);
}

void expect_orthonormal_frames(const MeshData& m) {
  expect_consistent(m);
  for (std::size_t v = 0; v < m.vertex_count(); ++v) {
    const glm::vec3 n = m.normals[v], t = glm::vec3(m.tangents[v]);
    ASSERT_TRUE(finite(m.positions[v]) && finite(n) && finite(t)) << "vertex " << v;
    EXPECT_NEAR(glm::length(n), 1.0f, kFrameTolerance) << "vertex " << v;
    EXPECT_NEAR(glm::length(t), 1.0f, kFrameTolerance) << "vertex " << v;
    EXPECT_NEAR(glm::dot(n, t), 0.0f, kFrameTolerance) << "vertex " << v;
    EXPECT_EQ(std::abs(m.tangents[v].w), 1.0f) << "vertex " << v;
  }
}

// Counter-clockwise seen from outside: the projected signed area along the vertex normals is positive.
void expect_ccw(const MeshData& m) {
  std::size_t checked = 0;
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    const std::uint32_t a = m.indices[3 * t], b = m.indices[3 * t + 1], c = m.indices[3 * t + 2];
    const glm::vec3 face = glm::cross(m.positions[b] - m.positions[a], m.positions[c] - m.positions[a]);
    if (glm::length(face) < 1e-9f) continue;
    ++checked;
    EXPECT_GT(glm::dot(face, m.normals[a] + m.normals[b] + m.normals[c]), 0.0f) << "triangle " << t;
  }
  EXPECT_GT(checked, 0u);
}

// The tangent points along +u and the bitangent w * cross(n, t) along +v of every adjacent triangle.
void expect_frames_follow_uvs(const MeshData& m) {
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    const std::uint32_t i[3] = {m.indices[3 * t], m.indices[3 * t + 1], m.indices[3 * t + 2]};
    const glm::vec3 e1 = m.positions[i[1]] - m.positions[i[0]], e2 = m.positions[i[2]] - m.positions[i[0]];
    const glm::vec2 d1 = m.uvs[i[1]] - m.uvs[i[0]], d2 = m.uvs[i[2]] - m.uvs[i[0]];
    const float det = d1.x * d2.y - d2.x * d1.y;
    if (std::abs(det) < 1e-9f || glm::length(glm::cross(e1, e2)) < 1e-9f) continue;
    const glm::vec3 dpdu = (e1 * d2.y - e2 * d1.y) / det, dpdv = (e2 * d1.x - e1 * d2.x) / det;
    for (const std::uint32_t v : i) {
      const glm::vec3 tangent(m.tangents[v]);
      const glm::vec3 bitangent = m.tangents[v].w * glm::cross(m.normals[v], tangent);
      EXPECT_GT(glm::dot(tangent, dpdu), 0.0f) << "triangle " << t << " vertex " << v;
      EXPECT_GT(glm::dot(bitangent, dpdv), 0.0f) << "triangle " << t << " vertex " << v;
    }
  }
}

void expect_well_formed(const MeshData& m) {
  expect_orthonormal_frames(m);
  expect_ccw(m);
  expect_frames_follow_uvs(m);
}

MeshDesc primitive(MeshKind kind) {
  MeshDesc d;
  d.kind = kind;
  return d;
}

std::string error_of(const MeshDesc& desc) {
  try {
    build_mesh(desc, kWhere);
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(Mesh, PlaneConventionExactly) {
  MeshDesc d = primitive(MeshKind::Plane);
  d.size = {4.0f, 2.0f};
  d.uv_scale = {3.0f, 5.0f};
  const MeshData m = build_mesh(d, kWhere);
  ASSERT_EQ(m.vertex_count(), 4u);
  ASSERT_EQ(m.triangle_count(), 2u);
  EXPECT_TRUE(m.triangle_materials.empty());
  EXPECT_TRUE(m.materials.empty());
  for (std::size_t v = 0; v < 4; ++v) {
    const glm::vec3 p = m.positions[v];
    EXPECT_EQ(p.z, 0.0f);
    EXPECT_EQ(std::abs(p.x), 2.0f);
    EXPECT_EQ(std::abs(p.y), 1.0f);
    // (0,0) at the (-x,-y) corner, uv_scale at (+x,+y).
    EXPECT_EQ(m.uvs[v], glm::vec2(p.x > 0 ? 3.0f : 0.0f, p.y > 0 ? 5.0f : 0.0f));
    EXPECT_EQ(m.normals[v], glm::vec3(0, 0, 1));
    EXPECT_EQ(m.tangents[v], glm::vec4(1, 0, 0, 1));
    EXPECT_EQ(m.tangents[v].w * glm::cross(m.normals[v], glm::vec3(m.tangents[v])), glm::vec3(0, 1, 0));
  }
  expect_well_formed(m);
}

TEST(Mesh, NegativeUvScaleFlipsTheFrame) {
  MeshDesc d = primitive(MeshKind::Plane);
  d.uv_scale = {-1.0f, 2.0f};
  const MeshData m = build_mesh(d, kWhere);
  for (const glm::vec4& t : m.tangents) EXPECT_EQ(t, glm::vec4(-1, 0, 0, -1));
  expect_well_formed(m);
}

TEST(Mesh, BoxHasFlatFacesWithFullUvRange) {
  MeshDesc d = primitive(MeshKind::Box);
  d.size = {3.0f, 0.0f};  // only x counts
  d.uv_scale = {2.0f, 2.0f};
  const MeshData m = build_mesh(d, kWhere);
  ASSERT_EQ(m.vertex_count(), 24u);
  ASSERT_EQ(m.triangle_count(), 12u);
  for (std::size_t v = 0; v < 24; ++v) {
    const glm::vec3 p = m.positions[v];
    EXPECT_EQ(std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)}), 1.5f);
    EXPECT_EQ(glm::dot(p, m.normals[v]), 1.5f);  // on its face's plane
    EXPECT_TRUE(m.uvs[v].x == 0.0f || m.uvs[v].x == 2.0f);
    EXPECT_TRUE(m.uvs[v].y == 0.0f || m.uvs[v].y == 2.0f);
  }
  expect_well_formed(m);
}

TEST(Mesh, SphereIsFiniteClosedAndOriented) {
  for (const int segments : {4, 7, 32, 64}) {
    SCOPED_TRACE(segments);
    MeshDesc d = primitive(MeshKind::Sphere);
    d.size = {2.0f, 0.0f};
    d.segments = segments;
    const MeshData m = build_mesh(d, kWhere);
    const int rings = segments / 2;
    EXPECT_EQ(m.triangle_count(), std::size_t(segments) * std::size_t(2 * rings - 2));
    for (std::size_t v = 0; v < m.vertex_count(); ++v) {
      EXPECT_NEAR(glm::length(m.positions[v]), 1.0f, 1e-6f);
      EXPECT_NEAR(glm::distance(m.positions[v], m.normals[v]), 0.0f, 1e-6f);
      EXPECT_GE(m.uvs[v].x, 0.0f);
      EXPECT_LE(m.uvs[v].x, 1.0f);
      if (std::abs(m.normals[v].z) == 1.0f) {
        // Poles: the tangent is the +u (eastward) direction of the vertex's longitude.
        const float phi = 2.0f * float(M_PI) * m.uvs[v].x;
        EXPECT_NEAR(m.tangents[v].x, -std::sin(phi), 1e-6f);
        EXPECT_NEAR(m.tangents[v].y, std::cos(phi), 1e-6f);
      }
    }
    // The seam column repeats the first one bit for bit.
    std::size_t seam = 0;
    for (std::size_t a = 0; a < m.vertex_count(); ++a)
      if (m.uvs[a].x == 1.0f)
        for (std::size_t b = 0; b < m.vertex_count(); ++b)
          if (m.uvs[b] == glm::vec2(0.0f, m.uvs[a].y)) {
            EXPECT_EQ(m.positions[a], m.positions[b]);
            ++seam;
          }
    EXPECT_EQ(seam, std::size_t(rings - 1));
    expect_well_formed(m);
  }
}

TEST(Mesh, FlatGridMatchesThePlane) {
  MeshDesc d = primitive(MeshKind::Grid);
  d.resolution = 3;
  d.size = {3.0f, 6.0f};
  const MeshData m = build_mesh(d, kWhere);
  ASSERT_EQ(m.vertex_count(), 16u);
  ASSERT_EQ(m.triangle_count(), 18u);
  for (std::size_t v = 0; v < 16; ++v) {
    EXPECT_EQ(m.positions[v], glm::vec3(1.0f * float(v % 4) - 1.5f, 2.0f * float(v / 4) - 3.0f, 0.0f));
    EXPECT_EQ(m.uvs[v], glm::vec2(float(v % 4) / 3.0f, float(v / 4) / 3.0f));
    EXPECT_EQ(m.normals[v], glm::vec3(0, 0, 1));
    EXPECT_EQ(m.tangents[v], glm::vec4(1, 0, 0, 1));
  }
  expect_well_formed(m);
}

TEST(Mesh, GridHeightMapDisplacesBilinearly) {
  test::TempDir dir;
  // 2x2 height map: h = 0 at (u,v) texel (0,0), 1 elsewhere. Files are read bottom-up (their last row is
  // v = 0), so the zero is the first value of the file's second row.
  test::write_file(dir / "h.pgm", "P2\n2 2\n255\n255 255\n0 255\n");
  MeshDesc d = primitive(MeshKind::Grid);
  d.resolution = 4;
  d.size = {2.0f, 2.0f};
  d.uv_scale = {3.0f, 3.0f};  // tiles materials; the height map covers the grid once
  d.height = 0.5f;
  d.height_map.source = TextureSource::File;
  d.height_map.file = dir / "h.pgm";
  const MeshData m = build_mesh(d, kWhere);
  ASSERT_EQ(m.vertex_count(), 25u);
  // Texel centres at s = 0.25 and 0.75: clamped up to them, linear between.
  const float h_at[5] = {0.0f, 0.0f, 0.5f, 1.0f, 1.0f};
  const auto z = [&](int i, int j) { return m.positions[std::size_t(j) * 5 + std::size_t(i)].z; };
  for (int j = 0; j < 5; ++j)
    for (int i = 0; i < 5; ++i) {
      // Bilinear: 1 - (1 - hu)(1 - hv) for this map.
      const float expected = 0.5f * (1.0f - (1.0f - h_at[i]) * (1.0f - h_at[j]));
      EXPECT_NEAR(z(i, j), expected, 1e-6f) << i << "," << j;
    }
  // Central differences: at (2,0) z rises by 0.5 over x in [-0.5, 0.5]; one-sided along y, which is flat there.
  EXPECT_NEAR(glm::distance(m.normals[2], glm::normalize(glm::vec3(-0.5f, 0.0f, 1.0f))), 0.0f, 1e-6f);
  // Along the far edge (j = 4) h = 1 everywhere: flat.
  EXPECT_NEAR(glm::distance(m.normals[4 * 5 + 2], glm::vec3(0, 0, 1)), 0.0f, 1e-6f);
  EXPECT_EQ(m.uvs[24], glm::vec2(3.0f, 3.0f));
  expect_well_formed(m);
}

TEST(Mesh, GridHeightMapErrorsNameTheField) {
  MeshDesc d = primitive(MeshKind::Grid);
  d.height = 1.0f;
  d.height_map.source = TextureSource::File;
  d.height_map.file = "/nonexistent/qdmr/h.png";
  EXPECT_NE(error_of(d).find(kWhere + "/height_map"), std::string::npos) << error_of(d);
}

TEST(Mesh, PrimitiveParameterErrors) {
  MeshDesc sphere = primitive(MeshKind::Sphere);
  sphere.segments = 3;
  EXPECT_EQ(error_of(sphere), kWhere + "/segments: must be at least 4 (got 3)");
  MeshDesc grid = primitive(MeshKind::Grid);
  grid.resolution = 0;
  EXPECT_EQ(error_of(grid), kWhere + "/resolution: must be at least 1 (got 0)");
  grid.resolution = 1 << 15;  // 2^31 triangles
  EXPECT_EQ(error_of(grid), kWhere + "/resolution: 2147483648 triangles exceed the limit of 268435456");
  MeshDesc plane = primitive(MeshKind::Plane);
  plane.size = {1.0f, -1.0f};
  EXPECT_EQ(error_of(plane), kWhere + "/size: both components must be positive and finite");
  plane.size = {1.0f, 1.0f};
  plane.uv_scale = {1.0f, 0.0f};
  EXPECT_EQ(error_of(plane), kWhere + "/uv_scale: both components must be finite and non-zero");
  MeshDesc box = primitive(MeshKind::Box);
  box.size = {NAN, 1.0f};
  EXPECT_EQ(error_of(box), kWhere + "/size: the first component must be positive and finite");
}

// --- compute_tangents ------------------------------------------------------------------------------------

MeshData one_triangle(glm::vec2 uv0, glm::vec2 uv1, glm::vec2 uv2) {
  MeshData m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  m.uvs = {uv0, uv1, uv2};
  m.indices = {0, 1, 2};
  return m;
}

TEST(Tangents, FollowUvDirectionsAndHandedness) {
  MeshData m = one_triangle({0, 0}, {0, 1}, {1, 0});  // u along +y, v along +x: mirrored
  compute_tangents(m);
  for (const glm::vec4& t : m.tangents) {
    EXPECT_NEAR(glm::distance(glm::vec3(t), glm::vec3(0, 1, 0)), 0.0f, 1e-6f);
    EXPECT_EQ(t.w, -1.0f);
  }
  expect_orthonormal_frames(m);
  expect_frames_follow_uvs(m);
}

TEST(Tangents, DegenerateUvsGiveAnyOrthogonalUnitVector) {
  for (const auto& uvs : {std::array<glm::vec2, 3>{}, std::array<glm::vec2, 3>{{{0, 0}, {1, 1}, {2, 2}}}}) {
    MeshData m = one_triangle(uvs[0], uvs[1], uvs[2]);
    m.normals.assign(3, glm::normalize(glm::vec3(1, 2, 3)));
    compute_tangents(m);
    expect_orthonormal_frames(m);
  }
}

TEST(Tangents, AreOrthogonalisedAgainstTheVertexNormal) {
  MeshData m = one_triangle({0, 0}, {1, 0}, {0, 1});
  m.normals.assign(3, glm::normalize(glm::vec3(1, 0, 1)));
  compute_tangents(m);
  for (const glm::vec4& t : m.tangents) {
    EXPECT_NEAR(glm::distance(glm::vec3(t), glm::normalize(glm::vec3(1, 0, -1))), 0.0f, 1e-6f);
    EXPECT_EQ(t.w, 1.0f);
  }
}

// --- OBJ --------------------------------------------------------------------------------------------------

MeshDesc obj(const std::filesystem::path& file) {
  MeshDesc d;
  d.kind = MeshKind::Obj;
  d.file = file;
  return d;
}

TEST(Obj, QuadWithUvsNormalsAndMaterials) {
  test::TempDir dir;
  std::filesystem::create_directories(dir / "mat");
  test::write_file(dir / "mat/lib.mtl",
                   "newmtl stone\n"
                   "Kd 0.5 0.5 0.5\n"
                   "map_Kd tex/albedo.png\n"
                   "norm tex/normal.png\n"
                   "bump -bm 0.5 tex/bump.png\n"
                   "disp tex/disp.png\n"
                   "newmtl painted\n"
                   "Kd 0.2 0.4 0.6\n"
                   "map_bump ../bump.png\n");
  test::write_file(dir / "quad.obj",
                   "mtllib mat/lib.mtl\n"
                   "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
                   "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                   "vn 0 0 2\n"
                   "f 1/1/1 2/2/1 3/3/1\n"
                   "usemtl stone\n"
                   "f 1/1/1 3/3/1 4/4/1\n"
                   "usemtl painted\n"
                   "f 1/1/1 2/2/1 3/3/1 4/4/1\n");
  // Every map an MTL file names must be a readable image when the OBJ loads (docs/scene-format.md).
  std::filesystem::create_directories(dir / "mat/tex");
  for (const char* map : {"mat/tex/albedo.png", "mat/tex/normal.png", "mat/tex/bump.png", "mat/tex/disp.png", "bump.png"}) {
    const std::string file = (dir / map).string();
    const unsigned char texel[3] = {128, 128, 255};
    auto out = OIIO::ImageOutput::create(file);
    ASSERT_TRUE(out && out->open(file, OIIO::ImageSpec(1, 1, 3, OIIO::TypeDesc::UINT8)) &&
                out->write_image(OIIO::TypeDesc::UINT8, texel) && out->close()) << file;
  }
  MeshDesc d = obj(dir / "quad.obj");
  d.uv_scale = {2.0f, 2.0f};
  const MeshData m = build_mesh(d, kWhere);
  EXPECT_EQ(m.vertex_count(), 4u);  // corners shared across faces
  ASSERT_EQ(m.triangle_count(), 4u);
  ASSERT_EQ(m.materials.size(), 3u);
  EXPECT_EQ(m.materials[0].name, "stone");
  EXPECT_EQ(m.materials[1].name, "painted");
  EXPECT_EQ(m.materials[2].name, "default");
  EXPECT_EQ(m.triangle_materials, (std::vector<std::uint32_t>{2, 0, 1, 1}));

  ASSERT_EQ(m.materials[0].layers.size(), 1u);
  const LayerDesc& stone = m.materials[0].layers[0];
  EXPECT_EQ(stone.albedo.source, TextureSource::File);
  EXPECT_EQ(stone.albedo.file, dir.path() / "mat/tex/albedo.png");
  EXPECT_EQ(stone.normal.source, TextureSource::File);
  EXPECT_EQ(stone.normal.file, dir.path() / "mat/tex/normal.png");
  EXPECT_EQ(stone.height.source, TextureSource::File);
  EXPECT_EQ(stone.height.file, dir.path() / "mat/tex/disp.png");  // disp wins over bump
  EXPECT_EQ(m.materials[0].technique.kind, TechniqueKind::Pom);   // and is displaced
  EXPECT_EQ(m.bump_maps, (std::vector<std::filesystem::path>{dir.path() / "mat/tex/bump.png", dir.path() / "bump.png", {}}));

  const LayerDesc& painted = m.materials[1].layers[0];
  EXPECT_EQ(painted.albedo.source, TextureSource::Constant);
  EXPECT_EQ(painted.albedo.constant, glm::vec4(0.2f, 0.4f, 0.6f, 1.0f));
  EXPECT_EQ(painted.normal.source, TextureSource::FromHeight);  // bump mapping: normals from the bump height
  EXPECT_EQ(m.materials[1].technique.kind, TechniqueKind::Normal);
  EXPECT_EQ(painted.height.file, dir.path() / "bump.png");
  EXPECT_TRUE(painted.height.file.is_absolute());

  EXPECT_EQ(m.materials[2].layers.at(0).albedo.source, TextureSource::Constant);
  EXPECT_EQ(m.materials[2].layers.at(0).albedo.constant, glm::vec4(1.0f));

  for (std::size_t v = 0; v < 4; ++v) {
    EXPECT_EQ(m.normals[v], glm::vec3(0, 0, 1));  // normalised
    EXPECT_EQ(m.uvs[v], glm::vec2(m.positions[v].x + 1.0f, m.positions[v].y + 1.0f));
    EXPECT_NEAR(glm::distance(glm::vec3(m.tangents[v]), glm::vec3(1, 0, 0)), 0.0f, 1e-6f);
    EXPECT_EQ(m.tangents[v].w, 1.0f);
  }
  expect_well_formed(m);
}

TEST(Obj, MissingNormalsAndUvsAreComputed) {
  test::TempDir dir;
  // A tetrahedron, counter-clockwise from outside, no vt/vn, no MTL.
  test::write_file(dir / "tet.obj",
                   "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                   "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  const MeshData m = build_mesh(obj(dir / "tet.obj"), kWhere);
  ASSERT_EQ(m.vertex_count(), 4u);
  ASSERT_EQ(m.triangle_count(), 4u);
  ASSERT_EQ(m.materials.size(), 1u);
  EXPECT_EQ(m.materials[0].name, "default");
  EXPECT_EQ(m.triangle_materials, (std::vector<std::uint32_t>(4, 0)));
  for (const glm::vec2& uv : m.uvs) EXPECT_EQ(uv, glm::vec2(0.0f));
  const auto normal_at = [&](glm::vec3 p) {
    for (std::size_t v = 0; v < m.vertex_count(); ++v)
      if (m.positions[v] == p) return m.normals[v];
    return glm::vec3(NAN);
  };
  // Area-weighted: the origin corner sees three unit right triangles.
  EXPECT_NEAR(glm::distance(normal_at({0, 0, 0}), glm::normalize(glm::vec3(-1, -1, -1))), 0.0f, 1e-6f);
  // (1,0,0): faces -z, -y (area 1/2) and the slanted one (area sqrt(3)/2, cross product (1,1,1)).
  const glm::vec3 expected = glm::normalize(glm::vec3(0, 0, -1) + glm::vec3(0, -1, 0) + glm::vec3(1, 1, 1));
  EXPECT_NEAR(glm::distance(normal_at({1, 0, 0}), expected), 0.0f, 1e-6f);
  expect_orthonormal_frames(m);
  expect_ccw(m);
}

TEST(Obj, TorusKnotAssetLoads) {
  const MeshData m = build_mesh(obj(test::source_dir() / "scenes/assets/torus_knot.obj"), kWhere);
  EXPECT_EQ(m.triangle_count(), 128u * 12u * 2u);
  ASSERT_EQ(m.materials.size(), 1u);  // every face has the MTL material: no default appended
  EXPECT_EQ(m.materials[0].name, "knot");
  EXPECT_EQ(m.materials[0].layers.at(0).albedo.source, TextureSource::Constant);
  for (const std::uint32_t id : m.triangle_materials) EXPECT_EQ(id, 0u);
  expect_well_formed(m);
}

std::string obj_error(const std::string& text, const std::string& mtl = "") {
  test::TempDir dir;
  test::write_file(dir / "m.obj", text);
  if (!mtl.empty()) test::write_file(dir / "m.mtl", mtl);
  try {
    build_mesh(obj(dir / "m.obj"), kWhere);
  } catch (const Error& e) {
    std::string message = e.what();
    // Make messages independent of the temp folder.
    for (std::size_t at; (at = message.find(dir.path().string())) != std::string::npos;)
      message.replace(at, dir.path().string().size(), "<tmp>");
    return message;
  }
  return "(no error)";
}

TEST(Obj, Errors) {
  const std::string where = kWhere + "/file: ";
  EXPECT_EQ(error_of(obj("/nonexistent/qdmr/m.obj")), where + "file not found: /nonexistent/qdmr/m.obj");
  {
    test::TempDir dir;
    EXPECT_EQ(error_of(obj(dir.path())), where + dir.path().lexically_normal().string() + " is a directory, not a file");
  }
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  // tinyobjloader reads "0e999" as 0 * 5^999 * 2^999 = 0 * inf = nan.
  EXPECT_EQ(obj_error("v 0 0 0\nv 0e999 0 0\nv 0 1 0\nf 1 2 3\n"),
            where + "position of vertex 2 is not finite: (nan, 0, 0)");
  // Overflowing literals are caught by the line check before tinyobjloader reads them.
  EXPECT_EQ(obj_error(tri + "vn 0 0 1e400\nf 1//1 2//1 3//1\n"),
            where + "line 4: normal component '1e400' is not a finite number");
  EXPECT_EQ(obj_error(tri + "vt 0 0\nvt 0e999 1\nf 1/1 2/2 3/1\n"),
            where + "texture coordinate 2 is not finite: (nan, 1)");
  EXPECT_EQ(obj_error(tri + "f 1 2 9\n"),
            where + "line 4: position index 9 in '9' is out of range (3 positions in the file)");
  EXPECT_EQ(obj_error(tri + "f 1 2 3 -4\n"),
            where + "line 4: position index -4 in '-4' is out of range (3 positions before this line)");
  EXPECT_EQ(obj_error(tri + "vt 0 0\nf 1/1 2/2 3/1\n"),
            where + "line 5: texture coordinate index 2 in '2/2' is out of range (1 texture coordinate in the file)");
  EXPECT_EQ(obj_error(tri + "f 1//1 2//1 3//1\n"),
            where + "line 4: normal index 1 in '1//1' is out of range (0 normals in the file)");
  EXPECT_EQ(obj_error(tri + "f 0 1 2\n"), where + "line 4: face index 0 in '0' (OBJ indices start at 1)");
  EXPECT_EQ(obj_error(tri + "f 1 2 x\n"), where + "line 4: cannot read the face index 'x' in 'x'");
  EXPECT_EQ(obj_error(tri), where + "no faces in <tmp>/m.obj");
  EXPECT_EQ(obj_error("mtllib nope.mtl\n" + tri + "f 1 2 3\n"), where + "material library not found: <tmp>/nope.mtl");
  EXPECT_EQ(obj_error("mtllib m.mtl\n" + tri + "usemtl other\nf 1 2 3\n", "newmtl one\nKd 1 1 1\n"),
            where + "material [ 'other' ] not found in .mtl");
}

}  // namespace
}  // namespace qdmr
