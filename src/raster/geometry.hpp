#pragma once
// Geometry stage: object vertices to clip space, near/far and guard-band clipping, back-face culling,
// viewport transform to fixed point. Output triangles keep submission order.
#include <array>
#include <cstdint>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec4.hpp>

#include "program/varyings.hpp"
#include "qdmr/core/pixel_buffer.hpp"

namespace qdmr {

struct MeshData;  // qdmr/mesh/mesh.hpp

struct ClipVertex {
  glm::vec4 clip;  // homogeneous clip-space position (GL convention: -w <= z <= w)
  std::array<float, kVaryingCount> varyings;
};

// One mesh instance to draw: the mesh, its model matrix and the frame-material index of each triangle.
struct DrawItem {
  const MeshData* mesh = nullptr;
  glm::mat4 model{1.0f};
  std::uint32_t material = 0;               // used when the mesh has no per-triangle materials
  std::vector<std::uint32_t> mesh_materials; // mesh-local material id -> frame material index
};

// A triangle ready for setup: fixed-point screen positions (y down), oriented so that the doubled
// signed area orient2d(p0, p1, p2) is positive, and its vertices (indices into GeometryResult::vertices).
struct ScreenTriangle {
  std::array<std::int32_t, 3> x, y;
  std::array<std::uint32_t, 3> vertex;
  std::uint32_t material;
};

struct ScreenVertex {
  float inv_w;   // 1 / clip w (w = view-space depth)
  float z;       // window depth in [0, 1]
  std::array<float, kVaryingCount> varyings;
};

struct GeometryCounters {
  std::uint64_t triangles_in = 0;
  std::uint64_t culled_backface = 0;    // back-facing or zero area after snapping
  std::uint64_t culled_outside = 0;     // entirely outside the view volume
  std::uint64_t clipped = 0;            // crossed near/far or the guard band and were clipped
  std::uint64_t triangles_out = 0;
};

// Large per-vertex and per-triangle arrays are filled in parallel: allocating them must not zero them serially.
template <class T>
using UninitVector = std::vector<T, DefaultInitAllocator<T>>;

struct GeometryResult {
  UninitVector<ScreenVertex> vertices;
  UninitVector<ScreenTriangle> triangles;
  GeometryCounters counters;
};

// A vertex's fixed-point screen position.
struct ScreenPoint {
  std::int32_t x = 0, y = 0;
};

// A vertex after the vertex stage: its screen vertex and fixed-point position.
struct ProjectedVertex {
  ScreenVertex vertex;
  ScreenPoint position;
};

// The vertices of one draw item after the vertex stage; their screen vertices go straight to the result's. Their
// clip-space vertices are not kept: the few triangles that need clipping make theirs again (the same operations,
// so the same bits), which spares a frame of small triangles 80 bytes written per vertex.
struct ItemVertices {
  UninitVector<unsigned> frustum_code, band_code;
  UninitVector<ScreenPoint> screen;  // valid where band_code == 0
};

// The triangles of one chunk of an item (assembled in parallel), with the vertices its clipping made.
struct GeometryChunk {
  std::vector<ScreenTriangle> triangles;
  std::vector<ScreenVertex> clipped_vertices;  // numbered with a local bit until the chunks are merged
  GeometryCounters counters;
};

// The stage's working arrays. A caller that keeps them (and the result) between frames lets a warm frame reuse
// their pages instead of faulting in fresh ones: about 100 MB a frame for a million triangles.
struct GeometryScratch {
  ItemVertices item;
  std::vector<GeometryChunk> chunks;
};

struct Viewport {
  int width = 0;
  int height = 0;
};

// Replaces `result` (its arrays' memory is kept) with the items' screen triangles and vertices.
void run_geometry(const std::vector<DrawItem>& items, const glm::mat4& view, const glm::mat4& projection,
                  const Viewport& viewport, GeometryScratch& scratch, GeometryResult& result);

}  // namespace qdmr
