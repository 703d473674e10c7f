// Signed distance functions of 2D shapes (negative inside, in the units of p) for coverage with
// pt_coverage(d, fw): an exact box-filter approximation along the edge normal.

float pt_sd_circle(float2 p, float r) { return length(p) - r; }

float pt_sd_box(float2 p, float2 half_size) {
  const float2 d = fabs(p) - half_size;
  return length(fmax(d, (float2)(0.0f))) + fmin(fmax(d.x, d.y), 0.0f);
}

// Box with corners rounded by radius r (clamped to the smaller half side).
float pt_sd_round_box(float2 p, float2 half_size, float r) {
  r = clamp(r, 0.0f, fmin(half_size.x, half_size.y));
  return pt_sd_box(p, half_size - r) - r;
}

float pt_sd_segment(float2 p, float2 a, float2 b) {
  const float2 pa = p - a, ba = b - a;
  const float h = clamp(dot(pa, ba) / fmax(dot(ba, ba), 1e-12f), 0.0f, 1.0f);
  return length(pa - ba * h);
}

// Superellipse |x/a|^n + |y/b|^n = 1: n = 1 diamond, 2 ellipse, large n a rectangle. Distance is
// the first-order estimate (F - 1) / |grad F| of the homogeneous norm F, evaluated with the
// components divided by their maximum so large exponents never overflow.
float pt_sd_superellipse(float2 p, float2 radii, float n) {
  const float2 u = fabs(p) / fmax(radii, (float2)(1e-6f));
  const float m = fmax(u.x, u.y);
  if (m < 1e-6f) return -fmin(radii.x, radii.y);
  const float2 v = u / m;
  const float s = pt_powr(v.x, n) + pt_powr(v.y, n);
  const float F = m * pt_powr(s, 1.0f / n);
  // dF/du_i = (u_i / F)^(n - 1); chain rule through u = |p| / radii.
  const float2 g = (float2)(pt_powr(u.x / F, n - 1.0f) / radii.x, pt_powr(u.y / F, n - 1.0f) / radii.y);
  const float gl = fmax(length(g), 1e-6f);
  // Far outside the estimate overshoots; the exact distance to a convex shape grows like |p|.
  return (F - 1.0f) / gl;
}

// n-pointed star with outer radius r and inner radius r * inner, first point along +x.
float pt_sd_star(float2 p, float r, int n, float inner) {
  const float sector = M_PI_F / (float)n;
  float a = pt_atan2(p.y, p.x);
  a = a - 2.0f * sector * pt_floor(a / (2.0f * sector));  // [0, 2 sector)
  if (a > sector) a = 2.0f * sector - a;                // mirror into [0, sector]
  const float len = length(p);
  const float2 q = len * (float2)(native_cos(a), native_sin(a));
  const float2 tip = (float2)(r, 0.0f);
  const float2 valley = r * inner * (float2)(native_cos(sector), native_sin(sector));
  const float d = pt_sd_segment(q, tip, valley);
  // Inside when q is on the origin's side of the edge tip -> valley.
  const float2 e = valley - tip;
  const float side = e.x * (q.y - tip.y) - e.y * (q.x - tip.x);
  return side < 0.0f ? d : -d;
}

// Regular hexagon with inner radius (apothem) r, flat sides top and bottom.
float pt_sd_hexagon(float2 p, float r) {
  const float3 k = (float3)(-0.866025404f, 0.5f, 0.577350269f);
  p = fabs(p);
  p -= 2.0f * fmin(dot(k.xy, p), 0.0f) * k.xy;
  p -= (float2)(clamp(p.x, -k.z * r, k.z * r), r);
  return length(p) * sign(p.y);
}

// Vesica (leaf / lens shape) along the y axis: intersection of two circles of radius r whose
// centres are 2d apart; half length sqrt(r^2 - d^2), half width r - d (after Inigo Quilez).
float pt_sd_vesica(float2 p, float r, float d) {
  p = fabs(p);
  const float b = sqrt(fmax(r * r - d * d, 0.0f));
  return ((p.y - b) * d > p.x * b) ? length(p - (float2)(0.0f, b)) : length(p + (float2)(d, 0.0f)) - r;
}

// Vesica from its half length and half width (half_width <= half_length).
float pt_sd_leaf(float2 p, float half_length, float half_width) {
  // r - d = hw, r^2 - d^2 = hl^2  =>  r + d = hl^2 / hw.
  const float s = half_length * half_length / fmax(half_width, 1e-6f);
  return pt_sd_vesica(p, 0.5f * (s + half_width), 0.5f * (s - half_width));
}
