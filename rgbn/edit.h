#pragma once
// Local edits of an RGBN as small serialisable operations (Pereira & Velho §1.5). An operation is
// a JSON object {"op": ..., parameters..., "region": ...}; an edit session is a list of them,
// replayed from the source image: the editor's undo and `proctex rgbn edit OPS.json` run the
// same code (apply_edit). Every edit is a rotation of normals on the sphere and keeps |n| = 1;
// an optional saturation bound xi (degrees) keeps n_z >= sin(xi).
//
// Operations (coordinates in pixels, x right, y down as in the image file):
//   {"op":"rotate", "target":[x,y,z], "amount":0.5, "mode":"replace"|"blend", "region":R, "xi":10}
//       every normal moves along its great arc towards target by `amount` of the arc (constant
//       speed, valid past 90 degrees); blend fades the amount to 0 at the region's rim.
//   {"op":"stamp", "at":[x,y], "shape":"dome"|"dimple"|"ring", "radius":16, "height":6,
//    "angle":0, "strength":1, "file":"stamp.exr", "albedo":"keep"|"replace"|"multiply", "xi":..}
//       a small RGBN (a file, band-passed by "detail":[s1,s2] if given, or a built-in shape)
//       applied in the local frame of the base normals at each target pixel: the current normals,
//       or with "base_sigma":S > 0 a bilateral-smoothed copy (sigma_s = S, normal range
//       "base_sigma_n", default 0.5: detail is smoothed, strong creases survive), so that the stamp
//       replaces the detail under it (Pereira & Velho's base normals). Pens take "base_sigma" too.
//   {"op":"pen", "points":[[x,y],...], "width":6, "depth":2, "profile":"groove"|"ridge"|"vee", "xi":..}
//       a height profile h(s) across a polyline (s = distance to the path); "vee" has a crease
//       on the medial axis.
//   {"op":"filter", "filter":"smooth"|"sharpen"|"edge"|"detail"|"scale"|"bilateral",
//    "sigma":2, "sigma2":6, "amount":1, "sigma_c":0.1, "sigma_n":0.2, "region":R}
//   {"op":"saturate", "xi":20, "region":R}   clamp normals to n_z >= sin(xi) along the meridian
//   {"op":"paint", "color":[r,g,b], "mode":"replace"|"multiply", "opacity":1, "region":R}
// Regions R: {"disc":[cx,cy,r], "feather":f} | {"rect":[x,y,w,h]} | {"mask":"file.png"} | absent
// (whole image). Pixels outside the footprint are never touched.
#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rgbn/filter.h"
#include "rgbn/rgbn.h"

namespace proctex::rgbn {

// --- rotations on the sphere ---------------------------------------------------------------
using Mat3 = std::array<std::array<double, 3>, 3>;
// Rotation about a x b taking a towards b by `t` of the arc angle (t = 1: a -> b exactly; works
// past 90 degrees; for antipodal a, b the axis is any one perpendicular to a).
Mat3 arc_rotation(const Vec3& a, const Vec3& b, double t);
Vec3 apply(const Mat3& r, const Vec3& v);
// Point at fraction t of the great arc from a to b (slerp).
Vec3 slerp(const Vec3& a, const Vec3& b, double t);
// The farthest point of the arc a -> b (or b itself) that keeps z >= sin(xi); if a is already
// below, its meridian point at z = sin(xi).
Vec3 saturate_on_arc(const Vec3& a, const Vec3& b, double xi_deg);
// Local frame of a normal n with in-plane orientation o: u = normalize(o - (o.n) n), v = n x u.
void local_frame(const Vec3& n, const Vec3& o, Vec3& u, Vec3& v);

// --- edits -----------------------------------------------------------------------------------
struct EditReport {
  std::string op;
  size_t pixels_changed = 0;
  std::array<int, 4> footprint{0, 0, 0, 0};  // x, y, w, h (bounding box of the touched pixels)
  double integrability_before = 0;          // mean |curl| over the footprint (+1 pixel)
  double integrability_after = 0;
  double milliseconds = 0;
};

// Applies one operation in place. `base_dir` resolves relative file names (stamps, masks).
// Throws UsageError for an unknown op or a malformed parameter.
EditReport apply_edit(Rgbn& image, const nlohmann::json& op, const std::filesystem::path& base_dir = {});
// Replays a session (a JSON array, or an object with "ops") on a copy of `source`; `upto`
// limits the number of operations (undo = replay fewer).
Rgbn apply_edits(const Rgbn& source, const nlohmann::json& session, std::vector<EditReport>* reports = nullptr,
                 const std::filesystem::path& base_dir = {}, int upto = -1);
nlohmann::json to_json(const EditReport& report);

// Built-in stamps: the normals of a height shape of `radius` pixels ("dome", "dimple", "ring").
Rgbn stamp_shape(const std::string& shape, float radius, float height);

}  // namespace proctex::rgbn
