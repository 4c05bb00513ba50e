#include "node_mass.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "shatter/kernel/error.hpp"

namespace shatter::detail {
namespace {

std::string short_number(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", x);
  return text;
}

}  // namespace

void require_fracturable_extent(const Mesh& mesh) {
  // Over the finite positions only: a NaN or an infinity is the input check's
  // to name (it runs after), and comparing one would raise.
  Vec3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
  for (const Vec3& p : mesh.positions) {
    if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) continue;
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  if (!(lo.x <= hi.x)) return;  // no finite position
  // Of halves, so that no difference overflows.
  const double half_widest = std::max({hi.x / 2 - lo.x / 2, hi.y / 2 - lo.y / 2, hi.z / 2 - lo.z / 2});
  if (!(half_widest <= 0x1p199)) {
    throw UnsupportedGeometryError("the solid is " + short_number(2 * half_widest) +
                                   " wide, more than 2^200 (1.6e60): its moments of inertia would not fit in doubles");
  }
}

bool storable_mass(const MassProperties& mass) {
  const auto finite = [](const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); };
  return mass.volume > 0 && std::isfinite(mass.volume) && finite(mass.centroid) &&
         std::all_of(mass.inertia.begin(), mass.inertia.end(), [](double entry) { return std::isfinite(entry); });
}

void require_representable_mass(const MassProperties& mass, std::string_view what) {
  if (storable_mass(mass)) return;
  throw UnsupportedGeometryError(std::string(what) + "'s volume is " + short_number(mass.volume) +
                                 " in doubles, not a positive double with finite moments: too small for its mass "
                                 "properties to be stored (about 1e-108 across or less)");
}

}  // namespace shatter::detail
