// proctex rgbn stamp / pen / edit: local edits as replayable JSON operations (rgbn/edit.h).
#include <fmt/format.h>

#include <filesystem>
#include <fstream>

#include "cli/cmd_rgbn.h"
#include "cli/output.h"
#include "core/error.h"
#include "rgbn/edit.h"

namespace proctex::cli::rgbn_cli {
namespace {
namespace fs = std::filesystem;
using namespace proctex::rgbn;
using nlohmann::json;

void report(const std::vector<EditReport>& reps, const std::string& output, bool as_json, bool quiet,
            const json& session) {
  if (as_json) {
    json j = {{"output", output}, {"edits", json::array()}, {"session", session}};
    for (const auto& r : reps) j["edits"].push_back(to_json(r));
    print_json(j);
    return;
  }
  if (quiet) return;
  for (size_t i = 0; i < reps.size(); ++i) {
    const auto& r = reps[i];
    std::printf("%zu %-8s %8zu px  integrability %.4g -> %.4g  %.2f ms\n", i + 1, r.op.c_str(), r.pixels_changed,
                r.integrability_before, r.integrability_after, r.milliseconds);
  }
  std::printf("%s\n", output.c_str());
}

struct EditOptions {
  std::string ops, input, output, preview, save_session;
  int upto = -1;
  bool json = false;
};

void run_edit(const EditOptions& o, const GlobalOptions& g) {
  std::ifstream in(o.ops);
  if (!in) throw Error("cannot read '" + o.ops + "'", "check the path of the edit session");
  json session;
  try {
    in >> session;
  } catch (const std::exception& e) {
    throw UsageError("'" + o.ops + "' is not valid JSON: " + e.what(), "an edit session is a JSON array of ops");
  }
  std::string source = o.input;
  if (source.empty() && session.is_object() && session.contains("source") && session["source"].is_string()) {
    fs::path p = session["source"].get<std::string>();
    if (p.is_relative()) p = fs::path(o.ops).parent_path() / p;
    source = p.string();
  }
  if (source.empty()) throw UsageError("no source RGBN", "give it after OPS.json or as \"source\" in the session");
  const Rgbn src = load_input(source);
  std::vector<EditReport> reps;
  const Rgbn out = apply_edits(src, session, &reps, fs::path(o.ops).parent_path(), o.upto);
  save_output(out, o.output, o.preview);
  report(reps, o.output, o.json, g.quiet, session);
}

// stamp and pen build one op, apply it, and can append it to a session file.
struct OneOpOptions {
  std::string input, output, preview, append;
  json op;
  bool json_out = false;
  // stamp
  std::vector<float> at;
  std::string shape = "dome", file, albedo;
  float radius = 16, height = 6, angle = 0, scale = 1, strength = 1;
  std::vector<float> detail;
  // pen
  std::vector<float> points;
  float width = 6, depth = 2;
  std::string profile = "groove";
  float xi = -90;
  float base_sigma = 0;
};

void run_one(const std::string& kind, OneOpOptions& o, const GlobalOptions& g) {
  json op = {{"op", kind}};
  if (kind == "stamp") {
    if (o.at.size() != 2) throw UsageError("--at needs x,y", "e.g. --at 120,80");
    op["at"] = o.at;
    if (!o.file.empty()) op["file"] = fs::absolute(o.file).string();
    else op["shape"] = o.shape, op["radius"] = o.radius, op["height"] = o.height;
    if (!o.albedo.empty()) op["albedo"] = o.albedo;
    if (o.detail.size() == 2) op["detail"] = o.detail;
    op["angle"] = o.angle, op["scale"] = o.scale, op["strength"] = o.strength;
  } else {
    if (o.points.size() < 2 || o.points.size() % 2) throw UsageError("--points needs x1,y1,x2,y2,...", "e.g. --points 10,10,200,60");
    json pts = json::array();
    for (size_t i = 0; i + 1 < o.points.size(); i += 2) pts.push_back({o.points[i], o.points[i + 1]});
    op["points"] = pts, op["width"] = o.width, op["depth"] = o.depth, op["profile"] = o.profile;
  }
  if (o.xi > -90) op["xi"] = o.xi;
  if (o.base_sigma != 0) op["base_sigma"] = o.base_sigma;
  Rgbn im = load_input(o.input);
  const EditReport r = apply_edit(im, op);
  save_output(im, o.output, o.preview);
  if (!o.append.empty()) {
    json session = json::array();
    if (fs::exists(o.append)) {
      std::ifstream in(o.append);
      try {
        in >> session;
      } catch (const std::exception&) {
        throw Error("'" + o.append + "' is not a JSON edit session", "give a new file or a JSON array");
      }
      if (!session.is_array()) throw Error("'" + o.append + "' is not a JSON array", "give a new file or a JSON array");
    }
    session.push_back(op);
    write_text_file(o.append, session.dump(2) + "\n");
  }
  report({r}, o.output, o.json_out, g.quiet, json::array({op}));
}

}  // namespace

void add_edit_commands(CLI::App& rgbn, GlobalOptions& global) {
  {
    auto o = std::make_shared<EditOptions>();
    auto* cmd = rgbn.add_subcommand("edit", "Replay an edit session (JSON list of operations) on an RGBN");
    cmd->footer(
        "An op is {\"op\": rotate|stamp|pen|filter|saturate|paint, parameters..., \"region\": {...}}:\n"
        "  [{\"op\":\"stamp\",\"at\":[120,80],\"shape\":\"dome\",\"radius\":20,\"height\":8},\n"
        "   {\"op\":\"pen\",\"points\":[[10,10],[200,60]],\"width\":5,\"depth\":2,\"profile\":\"vee\"},\n"
        "   {\"op\":\"rotate\",\"target\":[0.5,0,0.87],\"amount\":0.5,\"mode\":\"blend\",\"region\":{\"disc\":[64,64,30]}},\n"
        "   {\"op\":\"filter\",\"filter\":\"smooth\",\"sigma\":3,\"region\":{\"rect\":[0,0,100,100]}},\n"
        "   {\"op\":\"saturate\",\"xi\":20}, {\"op\":\"paint\",\"color\":[0.6,0.1,0.1],\"region\":{\"disc\":[50,50,10]}}]\n"
        "Optional \"xi\" (degrees) on any op keeps n_z >= sin(xi). Pixels outside a footprint are never changed.\n"
        "The session may be {\"source\": \"in.exr\", \"ops\": [...]}; --upto N replays the first N ops (undo).\n"
        "See docs/rgbn.md for every parameter.");
    cmd->add_option("ops", o->ops, "Edit session (.json)")->required();
    cmd->add_option("rgbn", o->input, "Source RGBN (.exr; default: the session's \"source\")");
    cmd->add_option("-o,--output", o->output, "Output RGBN (.exr)")->required();
    cmd->add_option("--upto", o->upto, "Replay only the first N operations");
    cmd->add_option("--preview", o->preview, "Also write a shaded preview image");
    cmd->add_flag("--json", o->json, "Print a JSON report (integrability before/after each op)");
    cmd->callback([o, &global] { run_edit(*o, global); });
  }
  {
    auto o = std::make_shared<OneOpOptions>();
    auto* cmd = rgbn.add_subcommand("stamp", "Apply a stamp (a small RGBN) in the local frame of the base normals");
    cmd->footer("  proctex rgbn stamp wall.exr --at 120,80 --shape dome --radius 20 --height 8 -o out.exr\n"
                "  proctex rgbn stamp wall.exr --at 120,80 --file rivet.exr --detail 1,6 --angle 30 -o out.exr");
    cmd->add_option("rgbn", o->input, "Input RGBN (.exr)")->required();
    cmd->add_option("-o,--output", o->output, "Output RGBN (.exr)")->required();
    cmd->add_option("--at", o->at, "Centre x,y in pixels")->delimiter(',')->required();
    cmd->add_option("--shape", o->shape, "Built-in stamp: dome, dimple or ring")->capture_default_str();
    cmd->add_option("--radius", o->radius, "Built-in stamp radius (pixels)")->capture_default_str();
    cmd->add_option("--height", o->height, "Built-in stamp height (pixels)")->capture_default_str();
    cmd->add_option("--file", o->file, "Stamp RGBN file instead of a shape");
    cmd->add_option("--detail", o->detail, "Band-pass the stamp first: sigma1,sigma2")->delimiter(',');
    cmd->add_option("--albedo", o->albedo, "keep, replace or multiply the albedo");
    cmd->add_option("--angle", o->angle, "Rotation in degrees (counter-clockwise)")->capture_default_str();
    cmd->add_option("--scale", o->scale, "Size factor")->capture_default_str();
    cmd->add_option("--strength", o->strength, "Slope factor (0 = no relief, 2 = twice as deep)")->capture_default_str();
    cmd->add_option("--xi", o->xi, "Saturation bound in degrees (n_z >= sin(xi))");
    cmd->add_option("--base-sigma", o->base_sigma,
                    "Compose on bilateral-smoothed base normals (sigma in pixels; 0 = the current normals)")
        ->capture_default_str();
    cmd->add_option("--append", o->append, "Append the operation to this session file");
    cmd->add_option("--preview", o->preview, "Also write a shaded preview image");
    cmd->add_flag("--json", o->json_out, "Print a JSON report");
    cmd->callback([o, &global] { run_one("stamp", *o, global); });
  }
  {
    auto o = std::make_shared<OneOpOptions>();
    auto* cmd = rgbn.add_subcommand("pen", "Draw a height profile along a polyline (groove, ridge, or vee crease)");
    cmd->footer("  proctex rgbn pen wall.exr --points 10,10,200,60,220,180 --width 5 --depth 2 --profile vee -o out.exr");
    cmd->add_option("rgbn", o->input, "Input RGBN (.exr)")->required();
    cmd->add_option("-o,--output", o->output, "Output RGBN (.exr)")->required();
    cmd->add_option("--points", o->points, "Polyline x1,y1,x2,y2,... in pixels")->delimiter(',')->required();
    cmd->add_option("--width", o->width, "Half width of the stroke (pixels)")->capture_default_str();
    cmd->add_option("--depth", o->depth, "Profile depth (pixels of height)")->capture_default_str();
    cmd->add_option("--profile", o->profile, "groove, ridge or vee (crease on the medial axis)")->capture_default_str();
    cmd->add_option("--xi", o->xi, "Saturation bound in degrees (n_z >= sin(xi))");
    cmd->add_option("--base-sigma", o->base_sigma,
                    "Compose on bilateral-smoothed base normals (sigma in pixels; 0 = the current normals)")
        ->capture_default_str();
    cmd->add_option("--append", o->append, "Append the operation to this session file");
    cmd->add_option("--preview", o->preview, "Also write a shaded preview image");
    cmd->add_flag("--json", o->json_out, "Print a JSON report");
    cmd->callback([o, &global] { run_one("pen", *o, global); });
  }
}

}  // namespace proctex::cli::rgbn_cli
