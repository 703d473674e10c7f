// @shader "Rust: corroded patches, pitting and run-off streaks on bare or painted metal"
// @param float amount       = 0.5  [0.05, 1]         "Fraction of the surface rusted"
// @param float scale        = 3    [1, 12] log       "Rust patches across the texture"
// @param color metal_color  = (0.35, 0.36, 0.38)     "Clean metal or paint colour (linear RGB)"
// @param color rust_color   = (0.45, 0.16, 0.04)     "Fresh orange rust (linear RGB)"
// @param color dark_color   = (0.10, 0.04, 0.02)     "Dark, deep rust (linear RGB)"
// @param float pitting      = 0.4  [0, 1]            "Dark pits in the rusted areas"
// @param float streaks      = 0.3  [0, 1]            "Rust running down in vertical streaks"
// @param float roughness    = 0.5  [0, 1]            "Texture within the rust"
// @param float grain        = 0.3  [0, 1]            "Fine grainy speckle of the corrosion (a photo's rust is grainy close up)"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float2 q = p * P.scale;
  const float w = fw * P.scale;
  const float n = pt_fbm(q, w, 6, 2.0f, 0.55f, pt_subseed(seed, 1u));
  // Streaks: the same kind of field stretched vertically, added below patches.
  const float st = pt_fbm((float2)(q.x * 3.0f, q.y * 0.3f), w * 3.0f, 4, 2.0f, 0.5f, pt_subseed(seed, 2u));
  const float field = n + P.streaks * 0.5f * st;
  // Threshold on a field of sd ~0.25-0.3; near amount 1 it drops further so the whole surface
  // can be rust (photographed rust is often wall to wall).
  const float t = 0.5f - P.amount - 0.35f * pow(P.amount, 4.0f);
  const float rust = pt_aa_threshold(field, t * 0.6f, 0.08f, w * 3.0f);
  // Rust colour: dark in the middle of patches, orange towards edges, varied by fine noise.
  const float f = pt_fbm(q * 6.0f, w * 6.0f, 4, 2.0f, 0.6f, pt_subseed(seed, 3u));
  const float depth = clamp((field - t * 0.6f) * 2.5f + 0.4f * P.roughness * f, 0.0f, 1.0f);
  float3 rc = mix(P.rust_color, P.dark_color, depth);
  rc *= 1.0f + 0.5f * P.roughness * f;
  // Grain: the flaking, pitted crust seen close up - light and dark specks a few pixels wide.
  const float g = pt_fbm(q * 25.0f, w * 25.0f, 3, 2.0f, 0.7f, pt_subseed(seed, 5u));
  rc = mix(rc * (1.0f + 1.6f * P.grain * g), P.dark_color, P.grain * clamp(-2.0f * g, 0.0f, 0.8f));
  // Pits: small dark cellular dots.
  // Only points nearer than the pit radius matter: the 2x2-cell search finds them (exact).
  const float pit_radius = 0.25f + w * 8.0f;
  const PtCellular c = pt_cellular_near(q * 8.0f, 1.0f, pit_radius, pt_subseed(seed, 4u));
  const float pit = P.pitting * (1.0f - smoothstep(0.05f, pit_radius, c.f1)) * step(0.6f, c.id);
  rc = mix(rc, P.dark_color * 0.5f, pit);
  float3 mc = P.metal_color * (1.0f + 0.1f * f);
  return pt_saturate3(mix(mc, rc, rust));
}
