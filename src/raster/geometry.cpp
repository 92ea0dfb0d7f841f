#include "raster/geometry.hpp"

#include <cmath>

#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>
#include <tbb/parallel_for.h>

#include "qdmr/core/limits.hpp"
#include "qdmr/mesh/mesh.hpp"

namespace qdmr {
namespace {

// Triangles are assembled in chunks of this many, in parallel; the chunking depends only on the mesh,
// so the output order (and every bit of it) is the same for any thread count.
constexpr std::size_t kTrianglesPerChunk = 16384;
// Vertices made by clipping are numbered per chunk with this bit set until the chunks are merged.
constexpr std::uint32_t kLocalVertex = 1u << 31;

// Planes as (a, b, c, d): inside when a*x + b*y + c*z + d*w >= 0 in clip space.
struct ClipPlane {
  glm::vec4 coefficients;
  double distance(const glm::vec4& v) const {
    return double(coefficients.x) * v.x + double(coefficients.y) * v.y + double(coefficients.z) * v.z +
           double(coefficients.w) * v.w;
  }
};

constexpr int kMaxPolygon = 3 + 6;  // a triangle clipped by 6 planes gains at most one vertex per plane

ClipVertex lerp(const ClipVertex& a, const ClipVertex& b, float t) {
  ClipVertex r;
  r.clip = a.clip + (b.clip - a.clip) * t;
  for (int i = 0; i < kVaryingCount; ++i) r.varyings[i] = a.varyings[i] + (b.varyings[i] - a.varyings[i]) * t;
  return r;
}

// Sutherland-Hodgman against one plane; returns the new vertex count.
int clip_polygon(const ClipVertex* in, int count, ClipVertex* out, const ClipPlane& plane) {
  int n = 0;
  for (int i = 0; i < count; ++i) {
    const ClipVertex& a = in[i];
    const ClipVertex& b = in[(i + 1) % count];
    const double da = plane.distance(a.clip);
    const double db = plane.distance(b.clip);
    if (da >= 0.0) out[n++] = a;
    if ((da >= 0.0) != (db >= 0.0)) out[n++] = lerp(a, b, float(da / (da - db)));
  }
  return n;
}

std::int64_t orient2d(const ScreenTriangle& t) {
  return std::int64_t(t.x[1] - t.x[0]) * (t.y[2] - t.y[0]) - std::int64_t(t.y[1] - t.y[0]) * (t.x[2] - t.x[0]);
}

// Bits: near, far, left, right, bottom, top; x/y tested against +-g*w (g = 1: the frustum, g > 1: the band).
unsigned outcode(const glm::vec4& c, float gx, float gy) {
  unsigned code = 0;
  if (!(c.z >= -c.w)) code |= 1u;
  if (!(c.z <= c.w)) code |= 2u;
  if (!(c.x >= -gx * c.w)) code |= 4u;
  if (!(c.x <= gx * c.w)) code |= 8u;
  if (!(c.y >= -gy * c.w)) code |= 16u;
  if (!(c.y <= gy * c.w)) code |= 32u;
  return code;
}

class Projection {
public:
  Projection(const Viewport& viewport) : viewport_(viewport) {
    // Guard band: in NDC the viewport spans [-1, 1]; the band extends it by kGuardBandPixels on each side.
    gx_ = 1.0f + 2.0f * float(limits::kGuardBandPixels) / float(viewport.width);
    gy_ = 1.0f + 2.0f * float(limits::kGuardBandPixels) / float(viewport.height);
    planes_ = {{
        {{0, 0, 1, 1}},      // near: z >= -w
        {{0, 0, -1, 1}},     // far:  z <= w
        {{1, 0, 0, gx_}},    // guard band left
        {{-1, 0, 0, gx_}},   // guard band right
        {{0, 1, 0, gy_}},    // guard band bottom
        {{0, -1, 0, gy_}},   // guard band top
    }};
  }

  float gx() const { return gx_; }
  float gy() const { return gy_; }
  const std::array<ClipPlane, 6>& planes() const { return planes_; }

  ProjectedVertex project(const ClipVertex& v) const {
    const double inv_w = 1.0 / double(v.clip.w);
    const double ndc_x = v.clip.x * inv_w, ndc_y = v.clip.y * inv_w, ndc_z = v.clip.z * inv_w;
    const double sx = (ndc_x * 0.5 + 0.5) * viewport_.width;
    const double sy = (0.5 - ndc_y * 0.5) * viewport_.height;
    ProjectedVertex p;
    p.vertex.inv_w = float(inv_w);
    p.vertex.z = float(ndc_z * 0.5 + 0.5);
    p.vertex.varyings = v.varyings;
    p.position.x = std::int32_t(std::floor(sx * limits::kSubpixelScale + 0.5));
    p.position.y = std::int32_t(std::floor(sy * limits::kSubpixelScale + 0.5));
    return p;
  }

private:
  Viewport viewport_;
  float gx_, gy_;
  std::array<ClipPlane, 6> planes_;
};

// The vertex stage of one draw item: a mesh vertex in clip space with its varyings.
class VertexStage {
public:
  VertexStage(const DrawItem& item, const glm::mat4& view_projection)
      : item_(item), view_projection_(view_projection), linear_(item.model),
        normal_matrix_(glm::transpose(glm::inverse(linear_))), mirrored_(glm::determinant(linear_) < 0.0f) {}

  bool mirrored() const { return mirrored_; }

  ClipVertex clip_vertex(std::size_t i) const {
    const MeshData& mesh = *item_.mesh;
    const glm::vec4 world = item_.model * glm::vec4(mesh.positions[i], 1.0f);
    const glm::vec3 nrm = glm::normalize(normal_matrix_ * mesh.normals[i]);
    const glm::vec4& t4 = mesh.tangents[i];
    const glm::vec3 t = glm::normalize(linear_ * glm::vec3(t4));
    ClipVertex v;
    v.clip = view_projection_ * world;
    const glm::vec4 w = mesh.blend_weights.empty() ? glm::vec4(0.0f) : mesh.blend_weights[i];
    v.varyings = {world.x, world.y, world.z, nrm.x, nrm.y, nrm.z, t.x, t.y, t.z, mirrored_ ? -t4.w : t4.w,
                  mesh.uvs[i].x, mesh.uvs[i].y, w.x, w.y, w.z, w.w};
    return v;
  }

private:
  const DrawItem& item_;
  glm::mat4 view_projection_;
  glm::mat3 linear_, normal_matrix_;
  bool mirrored_;
};

// Every vertex of the item through the vertex stage: its outcodes, and where it is inside the guard band its
// screen vertex (into `screen_vertices`) and position.
void transform_vertices(const DrawItem& item, const VertexStage& stage, const Projection& projection,
                        ItemVertices& out, ScreenVertex* screen_vertices) {
  const std::size_t n = item.mesh->vertex_count();
  out.frustum_code.resize(n);
  out.band_code.resize(n);
  out.screen.resize(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const auto& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const ClipVertex v = stage.clip_vertex(i);
      out.frustum_code[i] = outcode(v.clip, 1.0f, 1.0f);
      out.band_code[i] = outcode(v.clip, projection.gx(), projection.gy());
      if (out.band_code[i] != 0) continue;
      const ProjectedVertex p = projection.project(v);
      screen_vertices[i] = p.vertex;
      out.screen[i] = p.position;
    }
  });
}

class ChunkAssembler {
public:
  ChunkAssembler(const DrawItem& item, const VertexStage& stage, const ItemVertices& vertices,
                 const Projection& projection, std::uint32_t vertex_base, GeometryChunk& chunk)
      : item_(item), stage_(stage), vertices_(vertices), projection_(projection), vertex_base_(vertex_base),
        chunk_(chunk), mirrored_(stage.mirrored()) {}

  void triangle(std::size_t t) {
    const MeshData& mesh = *item_.mesh;
    const std::uint32_t material =
        mesh.triangle_materials.empty() ? item_.material : item_.mesh_materials[mesh.triangle_materials[t]];
    const std::uint32_t idx[3] = {mesh.indices[3 * t], mesh.indices[3 * t + 1], mesh.indices[3 * t + 2]};
    ++chunk_.counters.triangles_in;
    if ((vertices_.frustum_code[idx[0]] & vertices_.frustum_code[idx[1]] & vertices_.frustum_code[idx[2]]) != 0) {
      ++chunk_.counters.culled_outside;
      return;
    }
    if ((vertices_.band_code[idx[0]] | vertices_.band_code[idx[1]] | vertices_.band_code[idx[2]]) == 0) {
      const ScreenPoint* p[3] = {&vertices_.screen[idx[0]], &vertices_.screen[idx[1]], &vertices_.screen[idx[2]]};
      emit({vertex_base_ + idx[0], vertex_base_ + idx[1], vertex_base_ + idx[2]}, {p[0]->x, p[1]->x, p[2]->x},
           {p[0]->y, p[1]->y, p[2]->y}, material);
      return;
    }
    ++chunk_.counters.clipped;
    ClipVertex polygon_a[kMaxPolygon], polygon_b[kMaxPolygon];
    for (int k = 0; k < 3; ++k) polygon_a[k] = stage_.clip_vertex(idx[k]);
    int count = 3;
    ClipVertex* in = polygon_a;
    ClipVertex* out = polygon_b;
    for (const ClipPlane& plane : projection_.planes()) {
      count = clip_polygon(in, count, out, plane);
      std::swap(in, out);
      if (count < 3) break;
    }
    if (count < 3) {
      ++chunk_.counters.culled_outside;
      return;
    }
    ProjectedVertex projected[kMaxPolygon];
    std::uint32_t local[kMaxPolygon];
    for (int k = 0; k < count; ++k) {
      projected[k] = projection_.project(in[k]);
      local[k] = kLocalVertex | std::uint32_t(chunk_.clipped_vertices.size());
      chunk_.clipped_vertices.push_back(projected[k].vertex);
    }
    for (int k = 2; k < count; ++k)
      emit({local[0], local[k - 1], local[k]},
           {projected[0].position.x, projected[k - 1].position.x, projected[k].position.x},
           {projected[0].position.y, projected[k - 1].position.y, projected[k].position.y}, material);
  }

private:
  void emit(std::array<std::uint32_t, 3> vertex, std::array<std::int32_t, 3> x, std::array<std::int32_t, 3> y,
            std::uint32_t material) {
    ScreenTriangle t{x, y, vertex, material};
    // Front faces are counter-clockwise as seen on screen, which is negative orient2d in y-down screen
    // space; a mirroring model matrix flips that. Setup wants positive orientation, so front faces are swapped.
    const std::int64_t area = orient2d(t);
    const std::int64_t front_area = mirrored_ ? area : -area;
    if (front_area <= 0) {
      ++chunk_.counters.culled_backface;
      return;
    }
    if (area < 0) {
      std::swap(t.vertex[1], t.vertex[2]);
      std::swap(t.x[1], t.x[2]);
      std::swap(t.y[1], t.y[2]);
    }
    chunk_.triangles.push_back(t);
    ++chunk_.counters.triangles_out;
  }

  const DrawItem& item_;
  const VertexStage& stage_;
  const ItemVertices& vertices_;
  const Projection& projection_;
  std::uint32_t vertex_base_;
  GeometryChunk& chunk_;
  bool mirrored_;
};

}  // namespace

void run_geometry(const std::vector<DrawItem>& items, const glm::mat4& view, const glm::mat4& projection_matrix,
                  const Viewport& viewport, GeometryScratch& scratch, GeometryResult& result) {
  const glm::mat4 view_projection = projection_matrix * view;
  const Projection projection(viewport);
  result.vertices.clear();
  result.triangles.clear();
  result.counters = GeometryCounters{};

  // Vertices of every item first (their global indices are fixed), then each chunk's clipped vertices.
  std::vector<GeometryChunk>& chunks = scratch.chunks;  // the first `used` are this frame's
  std::size_t used = 0;
  for (const DrawItem& item : items) {
    ItemVertices& vertices = scratch.item;
    const VertexStage stage(item, view_projection);
    const std::uint32_t base = std::uint32_t(result.vertices.size());
    result.vertices.resize(result.vertices.size() + item.mesh->vertex_count());
    transform_vertices(item, stage, projection, vertices, result.vertices.data() + base);
    const std::size_t triangles = item.mesh->triangle_count();
    const std::size_t first_chunk = used;
    used += (triangles + kTrianglesPerChunk - 1) / kTrianglesPerChunk;
    if (chunks.size() < used) chunks.resize(used);
    tbb::parallel_for(first_chunk, used, [&](std::size_t c) {
      GeometryChunk& chunk = chunks[c];
      chunk.triangles.clear();
      chunk.clipped_vertices.clear();
      chunk.counters = GeometryCounters{};
      ChunkAssembler assembler(item, stage, vertices, projection, base, chunk);
      const std::size_t begin = (c - first_chunk) * kTrianglesPerChunk;
      const std::size_t end = std::min(triangles, begin + kTrianglesPerChunk);
      for (std::size_t t = begin; t < end; ++t) assembler.triangle(t);
    });
  }

  // Merge the chunks in order: prefix sums, then parallel copies with local vertex numbers made global.
  std::vector<std::size_t> triangle_offset(used + 1, 0), vertex_offset(used + 1, result.vertices.size());
  for (std::size_t c = 0; c < used; ++c) {
    triangle_offset[c + 1] = triangle_offset[c] + chunks[c].triangles.size();
    vertex_offset[c + 1] = vertex_offset[c] + chunks[c].clipped_vertices.size();
    const GeometryCounters& k = chunks[c].counters;
    result.counters.triangles_in += k.triangles_in;
    result.counters.culled_backface += k.culled_backface;
    result.counters.culled_outside += k.culled_outside;
    result.counters.clipped += k.clipped;
    result.counters.triangles_out += k.triangles_out;
  }
  result.vertices.resize(vertex_offset.back());
  result.triangles.resize(triangle_offset.back());
  tbb::parallel_for(std::size_t(0), used, [&](std::size_t c) {
    const GeometryChunk& chunk = chunks[c];
    std::copy(chunk.clipped_vertices.begin(), chunk.clipped_vertices.end(), result.vertices.begin() + std::ptrdiff_t(vertex_offset[c]));
    for (std::size_t i = 0; i < chunk.triangles.size(); ++i) {
      ScreenTriangle t = chunk.triangles[i];
      for (std::uint32_t& v : t.vertex)
        if (v & kLocalVertex) v = std::uint32_t(vertex_offset[c]) + (v & ~kLocalVertex);
      result.triangles[triangle_offset[c] + i] = t;
    }
  });
}

}  // namespace qdmr
