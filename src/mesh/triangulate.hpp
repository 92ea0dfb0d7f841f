#pragma once
// OBJ faces of any number of corners as triangles: ear clipping in the plane of the face's Newell normal, so
// concave faces (an L, a star, a terrain's outline) come out the way exporters mean them.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

namespace qdmr::mesh_detail {

struct PolygonTriangles {
  std::vector<std::uint32_t> corners;  // 3 per triangle, indices into the face's corners, in the face's winding
  bool degenerate = false;             // no area (collinear or coincident corners): no triangles
};

// Triangulates a face of 4 or more corners. Each ear is the corner whose triangle is convex and holds no other
// corner; a self-intersecting face, which has no such triangulation, is cut at its least concave corners
// instead (all its corners still used: n - 2 triangles). Throws qdmr::Error(where, ...) when a concave face needs
// more point-in-triangle tests than kMaxEarTests (a hostile file: about a second of work).
PolygonTriangles triangulate_polygon(std::span<const glm::dvec3> corners, const std::string& where);

inline constexpr std::uint64_t kMaxEarTests = std::uint64_t(1) << 28;

}  // namespace qdmr::mesh_detail
