#pragma once
// Multiscale exemplar graphs (Han 2011, ch. 4-5): exemplars E^0 (the root, coarsest), E^1, ... and
// edges (i, j, r): a pixel of E^i spans 2^r x 2^r pixels of E^j. Every exemplar has an implicit
// self edge (i, i, 0); a self edge with r > 0 ("E^i looks like itself at 2^r x") gives infinite zoom.
//
// This header holds the graph itself: the JSON file format, its validation, Han's admissible
// candidates and the level schedule (which stack levels a synthesis pixel may point to at each
// synthesis level). The synthesis on a graph is in graph_synthesis.h.
//
// JSON (paths relative to the file's folder; "scale" = 2^r, or give "r" itself):
//   {"exemplars": ["coarse.png", {"image": "fine.png", "tiles": "auto"}],
//    "edges": [{"from": 0, "to": 1, "scale": 4}, {"from": 1, "to": 1, "scale": 2}]}
#include <filesystem>
#include <string>
#include <vector>

namespace proctex::synth {

inline constexpr int kMaxGraphExemplars = 16;
inline constexpr int kMaxGraphZoom = 48;  // output pixel >= 2^-48 root texels (plane coordinates stay < 2^60)

struct GraphEdge {
  int from = 0, to = 0;
  int r = 0;  // a pixel of `from` spans 2^r x 2^r pixels of `to`
};

struct GraphExemplar {
  std::filesystem::path image;  // resolved against the graph file's folder
  std::string tiles = "auto";   // auto | yes | no: whether the exemplar itself tiles
};

struct ExemplarGraph {
  std::string name;  // the file, for messages
  std::vector<GraphExemplar> exemplars;
  std::vector<GraphEdge> edges;  // explicit edges only (the implicit (i, i, 0) are not listed)
};

// Parses a graph file / text: syntax, keys, indices, scales (powers of two), duplicate edges, and
// loops of scale-1 edges between different exemplars (colour offsets would accumulate around them
// without end). Throws proctex::Error naming the file and the offending entry.
ExemplarGraph parse_graph(const std::filesystem::path& file);
ExemplarGraph parse_graph_text(const std::string& text, const std::filesystem::path& base_dir,
                               const std::string& name);

// The checks that need the exemplars' stack depth L (levels 0..L): 2^r at most 2^(L-2) (a quarter of
// the exemplar, so source and destination scales overlap), and every exemplar reachable from the root.
void validate_graph(const ExemplarGraph& graph, int levels);

// A stack level E^exemplar_level.
struct StackLevel {
  int exemplar = 0, level = 0;
  bool operator==(const StackLevel& o) const { return exemplar == o.exemplar && level == o.level; }
  bool operator<(const StackLevel& o) const {
    return exemplar != o.exemplar ? exemplar < o.exemplar : level < o.level;
  }
};

// Han's admissible candidates A(E^i_k) = { E^j_l | (i, j, k - l) is an edge or the implicit self
// edge, 0 <= l < L }: the finest level L is never admissible (so pixels move on to finer exemplars),
// except with `finest_admissible` (we allow it at the output level). Sorted, no duplicates.
std::vector<StackLevel> admissible(const ExemplarGraph& graph, int levels, StackLevel from,
                                   bool finest_admissible = false);

// Han's superexemplar (fig. 5.1c): the stack levels at red depth t (synthesis level t), i.e. those
// reachable from E^0_0 by t upsampling steps and any correction steps along admissible edges
// (finest levels inadmissible). Sorted.
std::vector<StackLevel> superexemplar_level(const ExemplarGraph& graph, int levels, int depth);

// The level schedule of a synthesis whose output is at synthesis level T = L + zoom (an output pixel
// spans 2^-zoom root exemplar pixels): valid[t][i * (L + 1) + k] = 1 when a pixel may point to E^i_k
// after the correction at level t, i.e. E^i_k is reachable at depth t AND detail can still be
// found below it down to level T (so pixels are never stranded on an exemplar with no finer detail).
// At t = T the finest levels are admissible (the output shows each exemplar at full resolution).
struct LevelSchedule {
  int levels = 0;  // L
  int depth = 0;   // T
  std::vector<std::vector<unsigned char>> valid;  // [t = 0..T][node]
};
LevelSchedule level_schedule(const ExemplarGraph& graph, int levels, int zoom);

// The deepest zoom the graph supports (an output level whose pixels can all still find detail), or
// -1 when unbounded (a loop of edges with r > 0 reachable from the root: infinite zoom). Throws when
// even zoom 0 is impossible (cannot happen for a validated graph).
int max_zoom(const ExemplarGraph& graph, int levels);

}  // namespace proctex::synth
