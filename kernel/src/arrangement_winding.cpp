// Winding numbers of an arrangement's cells and the boundary of the cells the
// surface winds around (arrangement.hpp, winding_boundary). Every decision is
// on the vertices' exact rational coordinates.
#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include "order_around.hpp"
#include "shatter/kernel/arrangement.hpp"
#include "shatter/kernel/rationals.hpp"
#include "shatter/kernel/union_find.hpp"

namespace shatter {
namespace {

using Q3 = std::array<mpq_class, 3>;

Q3 minus(const Q3& x, const Q3& y) { return {x[0] - y[0], x[1] - y[1], x[2] - y[2]}; }
mpq_class dot(const Q3& x, const Q3& y) { return x[0] * y[0] + x[1] * y[1] + x[2] * y[2]; }
Q3 cross(const Q3& x, const Q3& y) {
  return {x[1] * y[2] - x[2] * y[1], x[2] * y[0] - x[0] * y[2], x[0] * y[1] - x[1] * y[0]};
}

// A face of the arrangement: a vertex triple, turned the way most of its
// pieces turn, and how many more pieces turn that way than the other.
struct Face {
  Triangle corners{};
  int count = 0;
  std::uint32_t source = 0;
};

class Winding {
 public:
  explicit Winding(const MeshArrangement& arrangement) : arrangement_(arrangement), set_(arrangement.plane_set()) {}

  WindingBoundary run() {
    WindingBoundary out;
    collect_faces(out);
    if (!closed()) {
      out.status = WindingBoundary::Status::open;
      return out;
    }
    UnionFind cells(2 * faces_.size());
    if (!join_around_edges(cells)) {
      out.status = WindingBoundary::Status::undecided;
      return out;
    }
    // Per cell (its representative node), the face sides in it.
    std::vector<std::vector<std::uint32_t>> sides(2 * faces_.size());
    std::vector<std::uint32_t> cell_of(2 * faces_.size());
    for (std::uint32_t node = 0; node < 2 * faces_.size(); ++node) {
      cell_of[node] = cells.find(node);
      sides[cell_of[node]].push_back(node);
      out.cells += cell_of[node] == node;
    }
    std::vector<std::optional<long>> winding(2 * faces_.size());
    std::vector<std::uint32_t> queue;
    for (std::uint32_t f = 0; f < faces_.size(); ++f) {
      if (winding[cell_of[front(f)]]) continue;
      const std::optional<long> seed = winding_in_front(f);
      ++out.seeds;
      if (!seed) {
        out.status = WindingBoundary::Status::undecided;
        return out;
      }
      winding[cell_of[front(f)]] = *seed;
      queue.assign(1, cell_of[front(f)]);
      // Crossing a face to its back raises the winding number by its count.
      while (!queue.empty()) {
        const std::uint32_t cell = queue.back();
        queue.pop_back();
        for (const std::uint32_t node : sides[cell]) {
          const std::uint32_t g = node / 2;
          const bool is_front = node % 2 == 0;
          const long across = *winding[cell] + (is_front ? faces_[g].count : -faces_[g].count);
          const std::uint32_t other = cell_of[is_front ? back(g) : front(g)];
          if (!winding[other]) {
            winding[other] = across;
            queue.push_back(other);
          } else if (*winding[other] != across) {
            out.status = WindingBoundary::Status::undecided;  // not closed after all
            return out;
          }
        }
      }
    }
    for (std::uint32_t f = 0; f < faces_.size(); ++f) {
      const long in_front = *winding[cell_of[front(f)]], behind = *winding[cell_of[back(f)]];
      out.max_winding = static_cast<int>(std::max<long>({out.max_winding, in_front, behind}));
      if ((behind >= 1) == (in_front >= 1)) continue;
      Triangle t = faces_[f].corners;
      if (in_front >= 1) std::swap(t[1], t[2]);
      out.triangles.push_back(t);
      out.source.push_back(faces_[f].source);
    }
    return out;
  }

 private:
  static std::uint32_t front(std::uint32_t f) { return 2 * f; }
  static std::uint32_t back(std::uint32_t f) { return 2 * f + 1; }

  void collect_faces(WindingBoundary& out) {
    std::map<Triangle, std::uint32_t> index;
    std::vector<Face> all;
    for (std::size_t k = 0; k < arrangement_.triangles.size(); ++k) {
      Triangle t = arrangement_.triangles[k];
      std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
      const bool plus = t[1] < t[2];
      if (!plus) std::swap(t[1], t[2]);
      const auto [it, inserted] = index.emplace(t, static_cast<std::uint32_t>(all.size()));
      if (inserted) all.push_back({t, 0, arrangement_.source[k]});
      all[it->second].count += plus ? 1 : -1;
    }
    out.faces = all.size();
    for (Face& face : all) {
      if (face.count == 0) {
        ++out.cancelled;
        continue;
      }
      if (face.count < 0) {
        std::swap(face.corners[1], face.corners[2]);
        face.count = -face.count;
      }
      faces_.push_back(face);
    }
    exact_.resize(arrangement_.defs.size());
    for (const Face& face : faces_) {
      for (const VertexIndex v : face.corners) {
        if (!exact_[v]) exact_[v] = exact_coordinates(set_, arrangement_.defs[v]);
      }
    }
    normal_.reserve(faces_.size());
    for (const Face& face : faces_) {
      const Q3 &a = point(face.corners[0]), &b = point(face.corners[1]), &c = point(face.corners[2]);
      normal_.push_back(cross(minus(b, a), minus(c, a)));
    }
  }

  const Q3& point(VertexIndex v) const { return *exact_[v]; }

  // Every edge passed as often one way as the other, faces counted with their counts.
  bool closed() {
    edges_.clear();
    for (std::uint32_t f = 0; f < faces_.size(); ++f) {
      const Triangle& t = faces_[f].corners;
      for (int k = 0; k < 3; ++k) {
        const VertexIndex u = t[k], v = t[(k + 1) % 3];
        edges_.push_back({{std::min(u, v), std::max(u, v)}, f});
      }
    }
    std::sort(edges_.begin(), edges_.end());
    for (std::size_t i = 0; i < edges_.size();) {
      std::size_t j = i;
      long net = 0;
      for (; j < edges_.size() && edges_[j].first == edges_[i].first; ++j) {
        const std::uint32_t f = edges_[j].second;
        net += forward(f, edges_[j].first.first, edges_[j].first.second) ? faces_[f].count : -faces_[f].count;
      }
      if (net != 0) return false;
      i = j;
    }
    return true;
  }

  // Whether face f passes its edge {a, b} from a to b.
  bool forward(std::uint32_t f, VertexIndex a, VertexIndex b) const {
    const Triangle& t = faces_[f].corners;
    for (int k = 0; k < 3; ++k) {
      if (t[k] == a && t[(k + 1) % 3] == b) return true;
    }
    return false;
  }

  // Around every edge a -> b, the faces in their exact order (the right-hand
  // turn about b - a), and each wedge between neighbours one cell: a face
  // passing a -> b has its front ahead in that turn (its normal is
  // (b - a) x (c - a)), one passing b -> a its back.
  bool join_around_edges(UnionFind& cells) {
    std::vector<std::uint32_t> around;
    std::vector<Q3> opposite;
    for (std::size_t i = 0; i < edges_.size();) {
      std::size_t j = i;
      around.clear();
      for (; j < edges_.size() && edges_[j].first == edges_[i].first; ++j) around.push_back(edges_[j].second);
      const auto [a, b] = edges_[i].first;
      i = j;
      const std::size_t k = around.size();
      std::vector<std::size_t> order{0, 1};
      if (k > 2) {
        opposite.clear();
        for (const std::uint32_t f : around) {
          for (const VertexIndex v : faces_[f].corners) {
            if (v != a && v != b) opposite.push_back(point(v));
          }
        }
        std::optional<std::vector<std::size_t>> sorted = kernel_detail::order_around_exact(point(a), point(b), opposite);
        if (!sorted) return false;
        order = std::move(*sorted);
      } else if (k < 2) {
        return false;  // closed() rules this out
      }
      for (std::size_t n = 0; n < k; ++n) {
        const std::uint32_t f = around[order[n]], g = around[order[(n + 1) % k]];
        const std::uint32_t after_f = forward(f, a, b) ? front(f) : back(f);
        const std::uint32_t before_g = forward(g, a, b) ? back(g) : front(g);
        cells.unite(after_f, before_g);
      }
    }
    return true;
  }

  // The winding number in front of face f: a ray from its centroid, in the
  // first of a fixed list of directions not along its plane that meets no
  // other face in an edge or a vertex and lies in no face's plane where it
  // could meet it; each face it crosses counts its count, positive where the
  // ray leaves through the face's front.
  std::optional<long> winding_in_front(std::uint32_t f) {
    const Triangle& t = faces_[f].corners;
    Q3 centre{};
    for (int c = 0; c < 3; ++c) centre[c] = (point(t[0])[c] + point(t[1])[c] + point(t[2])[c]) / 3;
    std::uint64_t state = 0x9e3779b97f4a7c15u;
    std::vector<signed char> side1(exact_.size()), side2(exact_.size());
    for (int attempt = 0; attempt < 64; ++attempt) {
      Q3 ray;
      for (int c = 0; c < 3; ++c) {
        state = state * 6364136223846793005u + 1442695040888963407u;
        ray[c] = static_cast<long>((state >> 33) % 195) - 97;
      }
      const int facing = sgn(dot(ray, normal_[f]));
      if (facing == 0) continue;  // along f's plane (the zero vector too)
      // Two planes through the ray's line: a face none of whose corners lies
      // on the other side of one of them is missed (or met on its boundary,
      // found below), which most faces are, decided by one sign per vertex.
      Q3 axis{1, 0, 0};
      if (sgn(ray[1]) == 0 && sgn(ray[2]) == 0) axis = {0, 1, 0};
      const Q3 u1 = cross(ray, axis), u2 = cross(ray, u1);
      for (std::size_t v = 0; v < exact_.size(); ++v) {
        if (!exact_[v]) continue;
        const Q3 from = minus(*exact_[v], centre);
        side1[v] = static_cast<signed char>(sgn(dot(u1, from)));
        side2[v] = static_cast<signed char>(sgn(dot(u2, from)));
      }
      long winding = 0;
      bool clear = true;
      for (std::uint32_t g = 0; g < faces_.size() && clear; ++g) {
        if (g == f) continue;
        const Triangle& c = faces_[g].corners;
        const auto one_side = [&](const std::vector<signed char>& s) {
          return (s[c[0]] > 0 && s[c[1]] > 0 && s[c[2]] > 0) || (s[c[0]] < 0 && s[c[1]] < 0 && s[c[2]] < 0);
        };
        if (one_side(side1) || one_side(side2)) continue;
        const mpq_class denominator = dot(normal_[g], ray);
        const mpq_class numerator = dot(normal_[g], minus(point(c[0]), centre));
        if (sgn(denominator) == 0) {
          // The ray runs along g's plane: a miss unless in it and then it may
          // graze g: try another direction.
          if (sgn(numerator) == 0) clear = false;
          continue;
        }
        // Met at or behind the centre: the centre is on g's plane only where g
        // lies beside f on its plane, or crosses it (no two faces cross).
        if (sgn(numerator) * sgn(denominator) <= 0) continue;
        const mpq_class along = numerator / denominator;
        const Q3 hit{centre[0] + along * ray[0], centre[1] + along * ray[1], centre[2] + along * ray[2]};
        int positive = 0, zero = 0;
        for (int e = 0; e < 3; ++e) {
          const int s =
              sgn(dot(cross(minus(point(c[(e + 1) % 3]), point(c[e])), minus(hit, point(c[e]))), normal_[g]));
          positive += s > 0;
          zero += s == 0;
        }
        if (positive + zero < 3) continue;  // outside g
        if (zero > 0) {
          clear = false;  // on an edge or a vertex of g
          continue;
        }
        winding += sgn(denominator) > 0 ? faces_[g].count : -faces_[g].count;
      }
      if (!clear) continue;
      // Pointing to f's back, the ray measured the winding number behind f.
      return facing > 0 ? winding : winding - faces_[f].count;
    }
    return std::nullopt;
  }

  const MeshArrangement& arrangement_;
  PlaneSet set_;
  std::vector<Face> faces_;
  std::vector<std::optional<Q3>> exact_;
  std::vector<Q3> normal_;
  std::vector<std::pair<std::pair<VertexIndex, VertexIndex>, std::uint32_t>> edges_;
};

}  // namespace

WindingBoundary winding_boundary(const MeshArrangement& arrangement) { return Winding(arrangement).run(); }

}  // namespace shatter
