#include "mesh/triangulate.hpp"

#include <cmath>
#include <string>

#include <glm/geometric.hpp>

#include "qdmr/core/error.hpp"

namespace qdmr::mesh_detail {
namespace {

struct Point {
  double x, y;
};

double cross(Point a, Point b, Point c) { return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x); }

// p inside or on the triangle abc (counter-clockwise).
bool in_triangle(Point p, Point a, Point b, Point c) {
  return cross(a, b, p) >= 0 && cross(b, c, p) >= 0 && cross(c, a, p) >= 0;
}

bool same(Point a, Point b) { return a.x == b.x && a.y == b.y; }

}  // namespace

PolygonTriangles triangulate_polygon(std::span<const glm::dvec3> corners, const std::string& where) {
  const std::size_t n = corners.size();
  PolygonTriangles result;
  // Newell's normal: twice the area vector, whatever the winding or the face's concavity.
  glm::dvec3 normal(0.0);
  double perimeter = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const glm::dvec3 &a = corners[i], &b = corners[(i + 1) % n];
    normal += glm::dvec3((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y));
    perimeter += glm::length(b - a);
  }
  const double area2 = glm::length(normal);
  // A face whose area is below 1e-12 of its perimeter squared has none worth a triangle (a circle's ratio is
  // 1/(4 pi)): collinear corners, or all in one point.
  if (!(area2 > 1e-12 * perimeter * perimeter)) {
    result.degenerate = true;
    return result;
  }
  // The face in its plane, counter-clockwise seen from the normal's side.
  const glm::dvec3 w = normal / area2;
  const glm::dvec3 u = glm::normalize(std::abs(w.x) > 0.9 ? glm::cross(w, glm::dvec3(0, 1, 0)) : glm::cross(w, glm::dvec3(1, 0, 0)));
  const glm::dvec3 v = glm::cross(w, u);
  std::vector<Point> p(n);
  for (std::size_t i = 0; i < n; ++i) p[i] = {glm::dot(corners[i], u), glm::dot(corners[i], v)};

  std::vector<std::uint32_t> prev(n), next(n);
  for (std::size_t i = 0; i < n; ++i) {
    prev[i] = std::uint32_t((i + n - 1) % n);
    next[i] = std::uint32_t((i + 1) % n);
  }
  const auto convex = [&](std::uint32_t i) { return cross(p[prev[i]], p[i], p[next[i]]) > 0; };
  // Only a corner that is not convex can lie inside an ear: they are the ones tested.
  std::vector<char> alive(n, 1), concave(n, 0);
  std::vector<std::uint32_t> concave_list;
  for (std::uint32_t i = 0; i < n; ++i)
    if (!convex(i)) {
      concave[i] = 1;
      concave_list.push_back(i);
    }
  std::uint64_t tests = 0;
  const auto is_ear = [&](std::uint32_t i) {
    if (concave[i]) return false;
    const Point a = p[prev[i]], b = p[i], c = p[next[i]];
    std::size_t kept = 0;
    bool ear = true;
    for (std::uint32_t k : concave_list) {
      if (!alive[k] || !concave[k]) continue;  // dropped from the list below
      concave_list[kept++] = k;
      if (!ear || k == prev[i] || k == next[i]) continue;
      ++tests;
      if (!same(p[k], a) && !same(p[k], b) && !same(p[k], c) && in_triangle(p[k], a, b, c)) ear = false;
    }
    concave_list.resize(kept);
    if (tests > kMaxEarTests)
      throw Error(where, "a concave face of " + std::to_string(n) + " corners (" + std::to_string(concave_list.size()) +
                             " of them concave) is too complex to triangulate");
    return ear;
  };
  const auto clip = [&](std::uint32_t i) {
    result.corners.insert(result.corners.end(), {prev[i], i, next[i]});
    alive[i] = 0;
    next[prev[i]] = next[i];
    prev[next[i]] = prev[i];
    for (std::uint32_t k : {prev[i], next[i]}) {  // a neighbour may turn convex (or, in a face that crosses
      const bool now = !convex(k);                  // itself, concave)
      if (now && !concave[k]) concave_list.push_back(k);
      concave[k] = now;
    }
  };
  result.corners.reserve(3 * (n - 2));
  std::size_t remaining = n, misses = 0;
  std::uint32_t at = 0;
  while (remaining > 3) {
    if (is_ear(at)) {
      const std::uint32_t following = next[at];
      clip(at);
      --remaining;
      misses = 0;
      at = following;
      continue;
    }
    at = next[at];
    if (++misses < remaining) continue;
    // A whole turn without an ear: the face crosses itself. Cut the convex corner with the smallest triangle,
    // else (no convex corner left) the flattest one.
    std::uint32_t best = at;
    double best_area = INFINITY;
    bool best_convex = false;
    std::uint32_t k = at;
    do {
      const double area = cross(p[prev[k]], p[k], p[next[k]]);
      const bool c = area > 0;
      if ((c && !best_convex) || (c == best_convex && std::abs(area) < best_area)) {
        best = k;
        best_area = std::abs(area);
        best_convex = c;
      }
      k = next[k];
    } while (k != at);
    at = next[best];
    clip(best);
    --remaining;
    misses = 0;
  }
  result.corners.insert(result.corners.end(), {prev[at], at, next[at]});
  return result;
}

}  // namespace qdmr::mesh_detail
