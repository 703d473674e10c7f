// @shader "Grass: a dense sward of lit, curved, overlapping blades in layers (lawn close up or far), clover, dry patches"
// @param float density     = 18   [6, 80] log         "Blade cells across the texture (small: close-up, large: lawn seen from afar)"
// @param float length      = 1.6  [0.5, 3]            "Blade length, in cells"
// @param float width       = 0.05 [0.02, 0.1] log     "Blade width at the base, as a fraction of its length"
// @param float direction   = 90   [0, 180]            "Mean blade direction in degrees (90: vertical)"
// @param float randomness  = 0.6  [0, 1]              "Spread of the blade directions (1: any direction)"
// @param color color       = (0.10, 0.25, 0.04)       "Blade colour (linear RGB)"
// @param color tip_color   = (0.35, 0.40, 0.15)       "Colour of dry tips and dry patches"
// @param color ground_color = (0.02, 0.03, 0.01)      "Shadowed ground between blades (linear RGB)"
// @param float variation   = 0.4  [0, 1]              "Blade-to-blade brightness and colour variation"
// @param float cover       = 2    [0.6, 3] log        "Blades over a point of ground on average (below 1 the ground shows)"
// @param float shading     = 0.6  [0, 1]              "Light and shade: blades lit on one side, darker deeper in the sward"
// @param float curl        = 0.3  [0, 1]              "Blade curvature (0: straight blades)"
// @param float clover      = 0.03 [0, 0.2]            "Share of small three-leaved clover among the blades"
// @param float patches     = 0.3  [0, 1]              "Large patches of lighter, drier grass across the lawn"

// Blades are drawn in GRASS_LAYERS layers, top first, composited front to back: a pixel stops
// looking deeper once it is covered. A blade reaches at most one lattice unit (half a blade
// length) from its centre. Each layer scatters the blades' centres over a grid of cells 2/3 of a
// unit wide, so the blades that can reach a pixel have their centres in the 4x4 cells nearest to
// it. Those 16 cells are tested in vector lanes (uint16/float16, one blade of each cell at a
// time): position, direction, curve, taper and the exact coverage condition, branch-free. Only a
// blade that covers the pixel (one or two per layer) is shaded, alone, from the geometry the
// lanes stored. Tested one by one (session 9), most of the time went to mispredicted branches on
// the many blades out of reach: 144 ms per 256^2 render against 43 ms now.
#define GRASS_LAYERS 3
#define GRASS_MAX_PER_CELL 10  // blades per lattice unit squared, per layer
#define GRASS_GRID 1.5f        // grid cells per lattice unit

// The 16 lanes' blade geometry, kept for the shading of the blades that cover the pixel.
typedef struct {
  float ox[16], oy[16], dx[16], dy[16], along[16], v[16], t[16], half_len[16];
  uint h[16], h2[16];
} GrassLanes;

// Which of the 16 cells of the window have a blade over the pixel, as bits (their geometry in
// *L). `state` holds each cell's random stream (a linear congruential step per blade, its high
// bits whitened by a shift).
uint grass_hits(const uint16 state, const uint k, const float16 qx, const float16 qy, const float n_cell,
                const float2 mean_dir, const float2 phi_ab, const uint clover_bits, const float2 len_ab,
                const float bend, const float hw0, const float w, __private GrassLanes* L) {
  const uint16 h = state ^ (state >> 15);
  uint16 h2 = h * 0x9e3779b1U;  // a second mix of the same bits
  h2 ^= h2 >> 16;
  // The fractional last blade of a cell, from the same 8 bits as its length.
  const float16 l8 = convert_float16(as_int16(h & 0xffU));
  const int16 active = l8 < (n_cell - (float)k) * 256.0f;
  // Position in the cell (12 bits each way), in lattice units.
  const float16 ox = qx - convert_float16(as_int16(h >> 20)) * (1.0f / (4096.0f * GRASS_GRID));
  const float16 oy = qy - convert_float16(as_int16((h >> 8) & 0xfffU)) * (1.0f / (4096.0f * GRASS_GRID));
  // Half length (0.6 + 0.35 u1) len_scale, direction phi (see the shading below).
  const float16 half_len = l8 * len_ab.x + len_ab.y;
  const float16 phi = convert_float16(as_int16((h2 >> 1) & 0xffffU)) * phi_ab.x + phi_ab.y;
  const float16 p2 = phi * phi;
  const float16 cr = 1.0f + p2 * (-0.5f + p2 * (1.0f / 24.0f - p2 * (1.0f / 720.0f)));
  const float16 sr = phi * (1.0f + p2 * (-1.0f / 6.0f + p2 * (1.0f / 120.0f - p2 * (1.0f / 5040.0f))));
  const float16 dx = mean_dir.x * cr - mean_dir.y * sr, dy = mean_dir.x * sr + mean_dir.y * cr;
  const float16 along_d = ox * dx + oy * dy;
  const float16 t = clamp(0.5f * along_d * native_recip(half_len) + 0.5f, 0.0f, 1.0f);
  const float16 t2 = t * t;
  // The side it curves to: bit 0 of h2 as the sign of the bend.
  const float16 curve = as_float16(as_uint16(bend * half_len * t2) ^ (h2 << 31));
  const float16 v = ox * dy - oy * dx - curve;
  const float16 hw = hw0 * 1.15f - (hw0 * t2) * t;
  const int16 blade_hit = (fabs(v) < fmax(hw, 0.5f * w) + 0.5f * w) & (fabs(along_d) < half_len + 0.5f * w);
  // Clover: three leaflets within 2.05 leaflet radii (0.16 half lengths) of the centre.
  const float16 rc = 0.33f * half_len + 0.5f * w;
  const int16 clover_hit = ox * ox + oy * oy < rc * rc;
  const int16 hit = active & select(blade_hit, clover_hit, (h2 >> 17) < clover_bits);
  const uint16 bit = as_uint16(hit) & (uint16)(1u, 2u, 4u, 8u, 16u, 32u, 64u, 128u, 256u, 512u, 1024u, 2048u, 4096u, 8192u, 16384u, 32768u);
  const uint8 b8 = bit.lo | bit.hi;
  const uint4 b4 = b8.lo | b8.hi;
  const uint2 b2 = b4.lo | b4.hi;
  const uint bits = b2.x | b2.y;
  if (bits != 0u) {
    vstore16(ox, 0, L->ox);
    vstore16(oy, 0, L->oy);
    vstore16(dx, 0, L->dx);
    vstore16(dy, 0, L->dy);
    vstore16(along_d, 0, L->along);
    vstore16(v, 0, L->v);
    vstore16(t, 0, L->t);
    vstore16(half_len, 0, L->half_len);
    vstore16(h, 0, L->h);
    vstore16(h2, 0, L->h2);
  }
  return bits;
}

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float a0 = radians(P.direction);
  const float2 mean_dir = (float2)(native_cos(a0), -native_sin(a0));
  // Light from the top left, as in the other nature shaders.
  const float2 light = (float2)(-0.7071f, -0.7071f);
  // Large-scale patches: drier, lighter grass in places (what a lawn seen from afar shows).
  const float pn = pt_fbm(p * 4.0f, fw * 4.0f, 3, 2.0f, 0.5f, pt_subseed(seed, 77u));
  const float dry = clamp(0.5f + 1.6f * pn, 0.0f, 1.0f) * P.patches;
  const float patch_light = 1.0f + 0.8f * P.patches * pn;
  // Mean blade area in cells (tapered blade: about 0.55 of the rectangle), and from it the
  // number of blades per lattice unit squared that gives the wanted cover over all layers.
  const float lat = 0.5f * P.length;  // lattice unit in cells
  const float blade_area = 0.78f * P.length * P.length * P.width * 0.55f;
  const float per_unit = fmin(P.cover * lat * lat / (GRASS_LAYERS * blade_area), (float)GRASS_MAX_PER_CELL);
  const float n_cell = per_unit / (GRASS_GRID * GRASS_GRID);  // blades per grid cell
  const int n_max = (int)ceil(n_cell);
  const uint clover_bits = (uint)(P.clover * 32768.0f);
  const float scale = P.density / lat;  // texture units -> lattice units
  const float w = fw * scale;           // pixel footprint in lattice units
  const float hw0 = P.width;  // half width at the base, lattice units (= width * length / 2)
  const float bend = 0.8f * P.curl;     // sideways bend at the tip, in half lengths
  const float reach_scale = sqrt(1.0f + bend * bend);  // centre to the bent tip, in half lengths
  const float len_scale = 1.0f / reach_scale;
  const float2 len_ab = (float2)(0.35f / 256.0f, 0.6f) * len_scale;
  const float2 phi_ab = (float2)(2.0f / 65536.0f, -1.0f) * (P.randomness * 1.5707963f);
  const int16 lane = (int16)(0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3);
  const int16 row = (int16)(0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3);

  float3 acc = (float3)(0.0f);
  float alpha = 0.0f;
  for (int layer = 0; layer < GRASS_LAYERS && alpha < 0.995f; ++layer) {
    const uint ls = pt_subseed(seed, (uint)layer);
    const float2 q = p * scale + (float2)(0.37f, 0.71f) * (float)layer;
    // Deeper layers are in the shade of the ones above.
    const float depth_light = 1.0f - P.shading * 0.35f * (float)layer;
    // The 4x4 grid cells around the pixel: at least 1.5 cells (one lattice unit) each way.
    const int x0 = (int)pt_floor(q.x * GRASS_GRID + 0.5f) - 2, y0 = (int)pt_floor(q.y * GRASS_GRID + 0.5f) - 2;
    const int16 cx = x0 + lane, cy = y0 + row;
    const uint16 hc = pt_hash16((as_uint16(cx) * 0x8da6b343U) ^ (as_uint16(cy) * 0xd8163841U) ^ ls);
    const float16 qx = q.x - convert_float16(cx) * (1.0f / GRASS_GRID);
    const float16 qy = q.y - convert_float16(cy) * (1.0f / GRASS_GRID);
    GrassLanes L;
    uint16 state = hc;
    for (int k = 0; k < n_max && alpha < 0.995f; ++k) {
      state = state * 1664525U + 1013904223U;
      uint bits = grass_hits(state, (uint)k, qx, qy, n_cell, mean_dir, phi_ab, clover_bits, len_ab, bend, hw0, w, &L);
      while (bits != 0u && alpha < 0.995f) {
        const int j = 31 - (int)clz(bits & (0u - bits));  // lowest set bit
        bits &= bits - 1u;
        // The blade of lane j, as grass_hits found it.
        const uint h = L.h[j], h2 = L.h2[j];
        const float2 off = (float2)(L.ox[j], L.oy[j]);
        const float2 dir = (float2)(L.dx[j], L.dy[j]);  // base -> tip
        const float half_len = L.half_len[j], along_d = L.along[j], v = L.v[j], t = L.t[j];
        const float u1 = (float)(h & 0xffU) * (1.0f / 256.0f);
        const float u0 = (float)((h2 >> 1) & 0xffffU) * (1.0f / 65536.0f);
        const bool is_clover = (h2 >> 17) < clover_bits;
        const float u3 = pt_u01(pt_hash(h2 ^ 0x85ebca6bU));
        float3 bc;
        float cover;
        if (is_clover) {
          // Clover: three round leaflets around the centre, lit from the light's side.
          const float rl = 0.16f * half_len;
          const float ta = 6.2831853f * u3;
          float best = 1e9f;
          float2 lo = (float2)(0.0f);
          for (int j = 0; j < 3; ++j) {
            const float aj = ta + 2.0943951f * (float)j;
            const float2 lc = off - 1.05f * rl * (float2)(native_cos(aj), native_sin(aj));
            const float d = length(lc) - rl;
            if (d < best) { best = d; lo = lc / rl; }
          }
          cover = pt_coverage(best, w);
          if (cover <= 0.0f) continue;
          bc = P.color * (1.0f + P.shading * (0.25f * dot(lo, -light) + 0.1f)) *
               (1.0f + P.variation * (u3 - 0.5f));
          bc *= 1.0f - 0.4f * P.shading * pt_detail_weight(rl / w) * smoothstep(0.7f, 1.0f, length(lo));
        } else {
          // Curved blade: the centre line leaves the straight axis by bend * t^2 towards the tip
          // (t: 0 base, 1 tip; v measured from the curved line).
          const float sign = (h2 & 1U) != 0U ? -1.0f : 1.0f;
          const float hw = hw0 * (1.15f - t * t * t);  // tapers to a point
          cover = pt_line_coverage(fabs(v), hw, w) * pt_coverage(fabs(along_d) - half_len, w);
          if (cover <= 0.0f) continue;
          // Colour: dry tips, dry patches, blade-to-blade variation.
          bc = mix(P.color, P.tip_color, clamp(t * t * t * (0.4f + u1) + dry * (0.3f + 0.7f * u3), 0.0f, 1.0f));
          // Brightness varies by up to +-1.5 stops from blade to blade (sunlit or shaded blades).
          bc *= native_exp2(3.0f * P.variation * (pt_fract(u3 * 13.7f + u0 * 5.3f) - 0.5f));
          // A blade is a folded ribbon: the half facing the light is brighter; a blade that
          // bends catches the light along its length; rims are darker (pixel-scale detail fades).
          // The two halves of the folded blade are flat: the light changes at the midrib.
          const float across = clamp(v / fmax(hw, 1e-5f), -1.0f, 1.0f);
          const float fold = clamp(v / (0.5f * w + 0.25f * hw + 1e-6f), -1.0f, 1.0f);
          const float2 nrm = (float2)(dir.y, -dir.x);
          const float facing = dot(nrm, -light) * fold;
          const float along = (u1 - 0.5f) * (2.0f * t - 1.0f) + sign * bend * 0.3f * t;
          const float dw = pt_detail_weight(4.0f * hw / w);
          // Under a pixel the fold and the rims fade to their mean across the blade (the rim
          // term averages -0.08), so the blade keeps its brightness at every resolution.
          const float a4 = across * across * across * across;
          bc *= fmax(1.0f + P.shading * (dw * (0.6f * facing - 0.4f * a4) - (1.0f - dw) * 0.08f +
                                         0.9f * along), 0.1f);
        }
        bc *= depth_light * patch_light;
        const float a = cover * (1.0f - alpha);
        acc += a * fmax(bc, 0.0f);
        alpha += a;
      }
    }
  }
  if (alpha >= 0.995f) return pt_saturate3(acc);
  // The ground under the sward: dark, a little uneven.
  const float3 ground = P.ground_color * (1.0f + 0.5f * pt_fbm(p * P.density, fw * P.density, 2, 2.0f, 0.5f,
                                                                 pt_subseed(seed, 91u))) * patch_light;
  return pt_saturate3(acc + (1.0f - alpha) * ground);
}
