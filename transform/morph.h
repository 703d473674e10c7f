#pragma once
// Texture transformation sequences (Bourque thesis chapter 5): from two or more textures in order
// (first, optional key-textures, last) to frames whose neighbours look alike.
//
//   catalog::Store store(db, catalog::Store::Access::Read);
//   Renderer renderer;
//   transform::Morph m = transform::plan({day, night}, store, renderer, {.frames = 120});
//   m.quality = transform::measure(m.frames, renderer, m.resolution, 0);
//
// Per pair of consecutive keys:
//   1. graph: the catalogue graph of the key's shader (edges weigh 1 - S); when the keys are in
//      different shaders, the graphs of every shader joined to them by jump edges (catalog link),
//      so a path may pass through a connective shader. Each key is joined to its closest catalogue
//      vertex (the thesis's snapping) and, when both keys share a shader, to the other key.
//      Beyond the thesis, between shaders: anchored jumps. For each shader t that catalog link
//      joined to a key's shader, the point of t that looks most like the key (search::refine at
//      morph time, jumps.h anchor_jump) is joined to the key by a jump edge, so the path can cross
//      where the two shaders look alike *at the key* instead of wandering to a jump point
//      anywhere in both domains;
//   2. Dijkstra with the power-n cost of eq 5.1 (path.h);
//   3. adaptive linear subdivision in the normalised parameter space (space.h) while adjacent
//      waypoints are less similar than `threshold`, up to `max_depth` halvings per catalogue edge
//      and `max_renders` renders in all; discrete parameters also halve until they change by one
//      whole step at a time. Edges that never reach the threshold are reported. Never across a
//      jump edge (the two ends live in different parameter spaces).
// Then, beyond the thesis:
//   4. frame timing: exactly `frames` frames, spaced evenly in perceptual distance (the metric's
//      distance -ln S summed along the path), keys and jump ends on frames of their own, `dissolve`
//      cross-faded frames at each jump, their blend weights at equal perceptual distances along
//      the cross-fade (measured on blends of the two ends' renders);
//   5. whole steps: a discrete parameter (rows, an enum) changes by one whole value at a time;
//      with `blend_steps` the frames that fall inside such a step cross-fade the renders of its
//      two ends instead of popping. Off by default: measured, the cross-fades are less similar to
//      their neighbours than the pop itself (docs/morph.md), though the layout changes less;
//   6. spatial coherence: one seed (the first input's) and one texture domain for every frame but
//      the keys themselves, so noise layouts do not jump between similar frames.
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "catalog/store.h"
#include "shaders/renderer.h"
#include "shaders/spec.h"
#include "transform/frames.h"

namespace proctex::transform {

struct MorphOptions {
  int frames = 120;
  double power = 3.0;       // eq 5.1 exponent n
  double threshold = 0.9;   // subdivision target for the similarity of adjacent waypoints
  int max_depth = 6;        // halvings per catalogue edge
  int max_renders = 800;    // subdivision renders for the whole morph
  int dissolve = 0;         // cross-faded frames at each jump
  bool connective = true;   // cross-shader segments may pass through other linked shaders
  bool anchor = true;       // cross-shader segments also get jumps anchored at their keys
  long anchor_evaluations = 160;  // renders per anchored jump (search::refine)
  bool blend_steps = false;  // frames inside a whole step of a discrete parameter cross-fade its ends
  int jobs = 0;             // metric threads (0: all cores)
};

// A point of the refined path.
struct Waypoint {
  std::string shader;
  std::vector<float> packed;
  std::string kind;   // "key", "vertex" (catalogue sample), "jump" (jump point of catalog link),
                      // "anchor" (jump point anchored at a key), "subdivision"
  int key = -1;       // input index of a key
  int sample = -1;    // catalogue sample index of a vertex
  int depth = 0;      // subdivision depth of the edge to the next waypoint
  metrics::Features features;  // analysis resolution, the path's seed
  // The edge to the next waypoint:
  double similarity = 1;
  bool jump = false;      // a jump edge (the next waypoint is in another shader)
  bool reached = true;    // similarity >= threshold, or a jump
  std::string note;       // why not reached: "depth cap", "render budget", "whole step of <param>"
  nlohmann::json to_json() const;
};

struct Morph {
  std::vector<TextureSpec> inputs;
  std::vector<Waypoint> path;
  std::vector<Frame> frames;
  std::vector<std::string> shaders;  // the shaders the path passes through, in order
  int jumps = 0;
  int resolution = 0;                // analysis resolution (the catalogue's)
  uint32_t seed = 0;                 // the path's seed
  MorphOptions options;
  std::vector<std::string> warnings;
  nlohmann::json stats = nlohmann::json::object();  // renders, seconds, graph sizes, path costs
  std::optional<Quality> quality, linear;           // filled by the caller (measure)

  int unreached_count() const;
  nlohmann::json unreached() const;
  nlohmann::json quality_json() const;  // both qualities and whether the morph beats linear
  nlohmann::json summary() const;       // everything but the frames and the path
  nlohmann::json manifest() const;      // summary + frames + path
};

struct MorphProgress {
  std::string stage;  // "keys", "path", "subdivide", "frames"
  double fraction = 0;
};

// Plans the frames (specs) of a morph. Throws UsageError for bad inputs (fewer than two, unknown
// shader, too few frames) and proctex::Error for an uncatalogued or stale shader and for shaders
// that no jump edges connect.
Morph plan(const std::vector<TextureSpec>& inputs, catalog::Store& store, Renderer& renderer, const MorphOptions& options,
           const std::function<void(const MorphProgress&)>& progress = {});

// The naive baseline with the same frame count and the same key frames: parameters interpolated
// linearly in the normalised space (whole values for discrete ones) between keys of one shader,
// a plain cross-fade between keys of different shaders. Same seed rule as plan().
std::vector<Frame> linear_frames(const std::vector<TextureSpec>& inputs, int frames, const ShaderLibrary& library);

}  // namespace proctex::transform
