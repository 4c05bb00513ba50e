#include "pslg_triangulator.hpp"

#include <gmpxx.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>
#include <map>
#include <unordered_map>
#include <unordered_set>

namespace seed_peer {
namespace {

using P2 = std::array<double, 2>;

// Exact signs. The filters are Shewchuk's "A" bounds for double inputs; below them
// the determinant is recomputed in rationals, which every double is exactly.
int orient2d(const P2& a, const P2& b, const P2& c) {
  const double l = (a[0] - c[0]) * (b[1] - c[1]);
  const double r = (a[1] - c[1]) * (b[0] - c[0]);
  const double det = l - r;
  const double bound = 3.3306690738754716e-16 * (std::fabs(l) + std::fabs(r));
  if (det > bound) return 1;
  if (-det > bound) return -1;
  const mpq_class ax(a[0]), ay(a[1]), bx(b[0]), by(b[1]), cx(c[0]), cy(c[1]);
  const mpq_class e = (ax - cx) * (by - cy) - (ay - cy) * (bx - cx);
  return sgn(e);
}

// > 0 when d is strictly inside the circle through a, b, c (counter-clockwise).
int incircle(const P2& a, const P2& b, const P2& c, const P2& d) {
  const double adx = a[0] - d[0], ady = a[1] - d[1];
  const double bdx = b[0] - d[0], bdy = b[1] - d[1];
  const double cdx = c[0] - d[0], cdy = c[1] - d[1];
  const double alift = adx * adx + ady * ady;
  const double blift = bdx * bdx + bdy * bdy;
  const double clift = cdx * cdx + cdy * cdy;
  const double det = alift * (bdx * cdy - cdx * bdy) + blift * (cdx * ady - adx * cdy) +
                     clift * (adx * bdy - bdx * ady);
  const double permanent = (std::fabs(bdx * cdy) + std::fabs(cdx * bdy)) * alift +
                           (std::fabs(cdx * ady) + std::fabs(adx * cdy)) * blift +
                           (std::fabs(adx * bdy) + std::fabs(bdx * ady)) * clift;
  const double bound = 1.1102230246251577e-15 * permanent;
  if (det > bound) return 1;
  if (-det > bound) return -1;
  const mpq_class qadx = mpq_class(a[0]) - mpq_class(d[0]), qady = mpq_class(a[1]) - mpq_class(d[1]);
  const mpq_class qbdx = mpq_class(b[0]) - mpq_class(d[0]), qbdy = mpq_class(b[1]) - mpq_class(d[1]);
  const mpq_class qcdx = mpq_class(c[0]) - mpq_class(d[0]), qcdy = mpq_class(c[1]) - mpq_class(d[1]);
  const mpq_class e = (qadx * qadx + qady * qady) * (qbdx * qcdy - qcdx * qbdy) +
                      (qbdx * qbdx + qbdy * qbdy) * (qcdx * qady - qadx * qcdy) +
                      (qcdx * qcdx + qcdy * qcdy) * (qadx * qbdy - qbdx * qady);
  return sgn(e);
}

std::uint64_t key(int u, int v) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(u)) << 32) | static_cast<std::uint32_t>(v);
}
std::uint64_t undirected(int u, int v) { return u < v ? key(u, v) : key(v, u); }

// A triangulation over points, with each directed edge mapped to the triangle that
// holds it (its twin's triangle is the neighbour across it).
struct Triangulation {
  std::vector<P2> pts;
  std::vector<std::array<int, 3>> tris;
  std::vector<char> alive;
  std::unordered_map<std::uint64_t, int> edge_tri;
  std::unordered_set<std::uint64_t> constrained;  // undirected keys

  int add(int a, int b, int c) {
    tris.push_back({a, b, c});
    alive.push_back(1);
    return static_cast<int>(tris.size()) - 1;
  }
  void index(int t) {
    const auto& v = tris[t];
    for (int i = 0; i < 3; ++i) edge_tri[key(v[i], v[(i + 1) % 3])] = t;
  }
  int third(int t, int u, int v) const {
    for (int w : tris[t])
      if (w != u && w != v) return w;
    return -1;
  }
  int tri_of(int u, int v) const {
    const auto it = edge_tri.find(key(u, v));
    return it == edge_tri.end() ? -1 : it->second;
  }
  // Flips edge (u, v) of t1 = (u, v, w) and t2 = (v, u, x) into (w, x): t1 becomes
  // (u, x, w) and t2 (x, v, w), both counter-clockwise when the quad is convex.
  void flip(int u, int v) {
    const int t1 = tri_of(u, v), t2 = tri_of(v, u);
    const int w = third(t1, u, v), x = third(t2, v, u);
    edge_tri.erase(key(u, v));
    edge_tri.erase(key(v, u));
    tris[t1] = {u, x, w};
    tris[t2] = {x, v, w};
    index(t1);
    index(t2);
  }
};

// Does segment (p, q) cross segment (a, b) at a point interior to both?
bool proper_cross(const Triangulation& T, int p, int q, int a, int b) {
  if (p == a || p == b || q == a || q == b) return false;
  const int s1 = orient2d(T.pts[a], T.pts[b], T.pts[p]);
  const int s2 = orient2d(T.pts[a], T.pts[b], T.pts[q]);
  if (s1 == 0 || s2 == 0 || s1 == s2) return false;
  const int s3 = orient2d(T.pts[p], T.pts[q], T.pts[a]);
  const int s4 = orient2d(T.pts[p], T.pts[q], T.pts[b]);
  return s3 != 0 && s4 != 0 && s3 != s4;
}

}  // namespace

PslgTriangulation triangulate_pslg(const Pslg& pslg) {
  PslgTriangulation out;
  const int n = static_cast<int>(pslg.points.size());
  if (n < 3) {
    out.error = "fewer than 3 points";
    return out;
  }
  // Exactly repeated points become their first occurrence (Triangle: "A duplicate
  // vertex ... appeared and was ignored").
  std::vector<int> rep(n);
  {
    std::map<P2, int> first;
    for (int i = 0; i < n; ++i) rep[i] = first.emplace(pslg.points[i], i).first->second;
  }
  Triangulation T;
  T.pts = pslg.points;
  double lo_x = pslg.points[0][0], hi_x = lo_x, lo_y = pslg.points[0][1], hi_y = lo_y;
  for (const auto& p : pslg.points) {
    if (!std::isfinite(p[0]) || !std::isfinite(p[1])) {
      out.error = "a non-finite point";
      return out;
    }
    lo_x = std::min(lo_x, p[0]);
    hi_x = std::max(hi_x, p[0]);
    lo_y = std::min(lo_y, p[1]);
    hi_y = std::max(hi_y, p[1]);
  }
  // A triangle far around every point; its corners are outside the domain, so the
  // triangles that touch them are eaten like Triangle's hull triangles.
  double span = std::max(hi_x - lo_x, hi_y - lo_y);
  if (!(span > 0)) span = 1;
  const double cx = 0.5 * (lo_x + hi_x), cy = 0.5 * (lo_y + hi_y);
  const int s0 = n, s1 = n + 1, s2 = n + 2;
  T.pts.push_back({cx - 20 * span, cy - 10 * span});
  T.pts.push_back({cx + 20 * span, cy - 10 * span});
  T.pts.push_back({cx, cy + 20 * span});
  T.add(s0, s1, s2);

  // Bowyer-Watson: the triangles whose circumcircle strictly holds the point form a
  // star-shaped cavity (exact signs), re-fanned from the point.
  std::unordered_map<std::uint64_t, int> cavity_edges;
  for (int i = 0; i < n; ++i) {
    if (rep[i] != i) continue;
    cavity_edges.clear();
    for (std::size_t t = 0; t < T.tris.size(); ++t) {
      if (!T.alive[t]) continue;
      const auto& v = T.tris[t];
      if (incircle(T.pts[v[0]], T.pts[v[1]], T.pts[v[2]], T.pts[i]) > 0) {
        T.alive[t] = 0;
        for (int k = 0; k < 3; ++k) cavity_edges[key(v[k], v[(k + 1) % 3])] = 1;
      }
    }
    for (const auto& [e, one] : cavity_edges) {
      const int u = static_cast<int>(e >> 32), v = static_cast<int>(e & 0xffffffffu);
      if (!cavity_edges.count(key(v, u))) T.add(u, v, i);
    }
  }
  // Compact and index the edges.
  {
    std::vector<std::array<int, 3>> kept;
    for (std::size_t t = 0; t < T.tris.size(); ++t)
      if (T.alive[t]) kept.push_back(T.tris[t]);
    T.tris = std::move(kept);
    T.alive.assign(T.tris.size(), 1);
    for (int t = 0; t < static_cast<int>(T.tris.size()); ++t) T.index(t);
  }

  // Segment recovery (Sloan's flips): flip every edge crossing the segment whose
  // quad is convex, until none crosses.
  std::unordered_set<std::uint64_t> done;
  for (const auto& seg : pslg.segments) {
    const int a = rep[seg[0]], b = rep[seg[1]];
    if (a == b || done.count(undirected(a, b))) continue;  // a zero-length or repeated segment
    done.insert(undirected(a, b));
    if (T.tri_of(a, b) < 0 && T.tri_of(b, a) < 0) {
      for (int w = 0; w < n; ++w) {
        if (rep[w] != w || w == a || w == b) continue;
        if (orient2d(T.pts[a], T.pts[b], T.pts[w]) != 0) continue;
        const int axis = std::fabs(T.pts[b][0] - T.pts[a][0]) >= std::fabs(T.pts[b][1] - T.pts[a][1]) ? 0 : 1;
        const double lo = std::min(T.pts[a][axis], T.pts[b][axis]), hi = std::max(T.pts[a][axis], T.pts[b][axis]);
        if (T.pts[w][axis] > lo && T.pts[w][axis] < hi) {
          out.error = "segment (" + std::to_string(seg[0]) + ", " + std::to_string(seg[1]) +
                      ") passes through point " + std::to_string(w);
          return out;
        }
      }
      std::deque<std::array<int, 2>> crossing;
      for (const auto& [e, t] : T.edge_tri) {
        const int u = static_cast<int>(e >> 32), v = static_cast<int>(e & 0xffffffffu);
        if (u < v && proper_cross(T, u, v, a, b)) {
          if (T.constrained.count(undirected(u, v))) {
            out.error = "segments (" + std::to_string(seg[0]) + ", " + std::to_string(seg[1]) +
                        ") and (" + std::to_string(u) + ", " + std::to_string(v) + ") cross";
            return out;
          }
          crossing.push_back({u, v});
        }
      }
      std::size_t budget = 50 * (crossing.size() + 1) * (crossing.size() + 1) + 1000;
      while (!crossing.empty()) {
        if (budget-- == 0) {
          out.error = "segment recovery did not finish";
          return out;
        }
        const auto [u, v] = crossing.front();
        crossing.pop_front();
        const int t1 = T.tri_of(u, v), t2 = T.tri_of(v, u);
        const int w = T.third(t1, u, v), x = T.third(t2, v, u);
        const int su = orient2d(T.pts[w], T.pts[x], T.pts[u]);
        const int sv = orient2d(T.pts[w], T.pts[x], T.pts[v]);
        if (su == 0 || sv == 0 || su == sv) {  // not strictly convex: later
          crossing.push_back({u, v});
          continue;
        }
        T.flip(u, v);
        if (proper_cross(T, w, x, a, b)) crossing.push_back({w, x});
      }
    }
    T.constrained.insert(undirected(a, b));
  }

  // Lawson flips back to the constrained Delaunay triangulation.
  std::vector<std::array<int, 2>> stack;
  for (const auto& [e, t] : T.edge_tri) {
    const int u = static_cast<int>(e >> 32), v = static_cast<int>(e & 0xffffffffu);
    if (u < v) stack.push_back({u, v});
  }
  while (!stack.empty()) {
    const auto [u, v] = stack.back();
    stack.pop_back();
    if (T.constrained.count(undirected(u, v))) continue;
    const int t1 = T.tri_of(u, v), t2 = T.tri_of(v, u);
    if (t1 < 0 || t2 < 0) continue;
    const int w = T.third(t1, u, v), x = T.third(t2, v, u);
    if (incircle(T.pts[u], T.pts[v], T.pts[w], T.pts[x]) <= 0) continue;
    T.flip(u, v);
    stack.push_back({u, x});
    stack.push_back({x, v});
    stack.push_back({v, w});
    stack.push_back({w, u});
  }

  // Eat from the outside and from every hole point, stopping at segments.
  std::vector<char> eaten(T.tris.size(), 0);
  std::vector<int> queue;
  for (int t = 0; t < static_cast<int>(T.tris.size()); ++t) {
    const auto& v = T.tris[t];
    if (v[0] >= n || v[1] >= n || v[2] >= n) {
      eaten[t] = 1;
      queue.push_back(t);
    }
  }
  for (const auto& h : pslg.holes) {
    for (int t = 0; t < static_cast<int>(T.tris.size()); ++t) {
      const auto& v = T.tris[t];
      if (orient2d(T.pts[v[0]], T.pts[v[1]], h) >= 0 && orient2d(T.pts[v[1]], T.pts[v[2]], h) >= 0 &&
          orient2d(T.pts[v[2]], T.pts[v[0]], h) >= 0) {
        if (!eaten[t]) {
          eaten[t] = 1;
          queue.push_back(t);
        }
        break;
      }
    }
  }
  while (!queue.empty()) {
    const int t = queue.back();
    queue.pop_back();
    const auto v = T.tris[t];
    for (int k = 0; k < 3; ++k) {
      const int a = v[k], b = v[(k + 1) % 3];
      if (T.constrained.count(undirected(a, b))) continue;
      const int o = T.tri_of(b, a);
      if (o >= 0 && !eaten[o]) {
        eaten[o] = 1;
        queue.push_back(o);
      }
    }
  }
  for (int t = 0; t < static_cast<int>(T.tris.size()); ++t)
    if (!eaten[t]) out.triangles.push_back(T.tris[t]);
  out.ok = true;
  return out;
}

}  // namespace seed_peer
