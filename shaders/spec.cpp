#include "shaders/spec.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "image/image.h"

namespace proctex {
namespace {

using nlohmann::json;

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  const auto e = s.find_last_not_of(" \t");
  return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
}

// Splits on commas that are not inside parentheses or brackets.
std::vector<std::string> split_top_level(const std::string& text) {
  std::vector<std::string> out;
  std::string current;
  int depth = 0;
  for (char c : text) {
    if (c == '(' || c == '[') ++depth;
    if (c == ')' || c == ']') --depth;
    if (c == ',' && depth == 0) {
      out.push_back(trim(current));
      current.clear();
    } else {
      current += c;
    }
  }
  if (!trim(current).empty() || !out.empty()) out.push_back(trim(current));
  return out;
}

json parse_hex_color(const std::string& v) {
  if (v.size() != 7) throw UsageError("colour '" + v + "' is not #rrggbb", "write e.g. #a0522d");
  json rgb = json::array();
  for (int i = 0; i < 3; ++i) {
    const int byte = std::stoi(v.substr(1 + 2 * i, 2), nullptr, 16);
    rgb.push_back(srgb_to_linear(byte / 255.0f));
  }
  return rgb;
}

// Inline values: number, bool, enum name, (r,g,b) or #rrggbb.
json parse_inline_value(const std::string& key, const std::string& raw) {
  const std::string v = trim(raw);
  if (v.empty()) throw UsageError("parameter '" + key + "' has no value", "write " + key + "=VALUE");
  if (v == "true") return true;
  if (v == "false") return false;
  if (v[0] == '#') return parse_hex_color(v);
  if (v.front() == '(' || v.front() == '[') {
    json arr = json::array();
    for (const auto& part : split_top_level(v.substr(1, v.size() - 2))) arr.push_back(parse_inline_value(key, part));
    return arr;
  }
  char* end = nullptr;
  const double d = std::strtod(v.c_str(), &end);
  if (end == v.c_str() + v.size()) {
    if (v.find_first_of(".eE") == std::string::npos) return static_cast<int64_t>(std::llround(d));
    return d;
  }
  return v;  // an enum name
}

[[noreturn]] void bad_value(const ShaderDecl& decl, const ParamDecl& p, const std::string& why) {
  std::string range;
  if (p.type == ParamType::Enum) {
    for (const auto& v : p.enum_values) range += (range.empty() ? "" : ", ") + v;
    range = "one of {" + range + "}";
  } else if (p.type == ParamType::Bool) {
    range = "true or false";
  } else {
    std::ostringstream r;
    r << "[" << p.min << ", " << p.max << "]";
    range = (p.type == ParamType::Color ? "3 numbers in " : "a number in ") + r.str();
  }
  throw UsageError(decl.name + "." + p.name + ": " + why + " (" + to_string(p.type) + ", " + range + ")",
                   "see 'proctex shaders show " + decl.name + "'");
}

float checked_number(const ShaderDecl& decl, const ParamDecl& p, const json& v) {
  if (!v.is_number()) bad_value(decl, p, "expected a number, got " + v.dump());
  const double d = v.get<double>();
  // Compared in float, the declared bounds' type: 0.05 as typed is below 0.05f.
  if (!std::isfinite(d) || static_cast<float>(d) < p.min || static_cast<float>(d) > p.max)
    bad_value(decl, p, "value " + v.dump() + " is out of range");
  if (p.type == ParamType::Int && d != std::round(d))
    bad_value(decl, p, "value " + v.dump() + " is not an integer");
  return static_cast<float>(d);
}

void pack_value(const ShaderDecl& decl, const ParamDecl& p, const json& v, float* out) {
  switch (p.type) {
    case ParamType::Float:
    case ParamType::Int:
      out[0] = checked_number(decl, p, v);
      return;
    case ParamType::Bool:
      if (v.is_boolean()) out[0] = v.get<bool>() ? 1.0f : 0.0f;
      else if (v.is_number_integer() && (v == 0 || v == 1)) out[0] = v.get<float>();
      else bad_value(decl, p, "expected true or false, got " + v.dump());
      return;
    case ParamType::Color: {
      json c = v;
      if (c.is_string() && c.get<std::string>().starts_with("#")) c = parse_hex_color(c.get<std::string>());
      if (c.is_number()) c = json::array({c, c, c});  // a grey level
      if (!c.is_array() || c.size() != 3) bad_value(decl, p, "expected [r, g, b], got " + v.dump());
      for (int i = 0; i < 3; ++i) out[i] = checked_number(decl, p, c[i]);
      return;
    }
    case ParamType::Enum: {
      if (v.is_string()) {
        const auto& values = p.enum_values;
        const auto it = std::find(values.begin(), values.end(), v.get<std::string>());
        if (it == values.end()) bad_value(decl, p, "unknown value " + v.dump());
        out[0] = static_cast<float>(it - values.begin());
      } else {
        out[0] = checked_number(decl, p, v);  // an index is accepted too
      }
      return;
    }
  }
}

}  // namespace

json TextureSpec::to_json() const {
  json params_json = json::object();
  for (const auto& [k, v] : params) params_json[k] = v;
  return json{{"shader", shader}, {"params", params_json}, {"seed", seed}};
}

TextureSpec TextureSpec::from_json(const json& j) {
  if (!j.is_object() || !j.contains("shader") || !j["shader"].is_string())
    throw UsageError("a texture spec needs a \"shader\" name",
                     R"(write {"shader": "bricks", "params": {...}, "seed": 0})");
  TextureSpec spec;
  spec.shader = j["shader"].get<std::string>();
  if (j.contains("params")) {
    if (!j["params"].is_object()) throw UsageError("\"params\" must be an object", "write \"params\": {\"name\": value}");
    for (const auto& [k, v] : j["params"].items()) spec.params[k] = v;
  }
  if (j.contains("seed")) {
    const auto& s = j["seed"];
    if (!s.is_number_integer() || s.get<int64_t>() < 0 || s.get<int64_t>() > 0xffffffffLL)
      throw UsageError("\"seed\" must be an integer in [0, 4294967295]", "fix the seed");
    spec.seed = static_cast<uint32_t>(s.get<int64_t>());
  }
  return spec;
}

TextureSpec parse_spec_argument(const std::string& argument) {
  namespace fs = std::filesystem;
  // error_code: an inline spec longer than a file name may be (255 bytes) is not a file, not an error.
  std::error_code ec;
  if (argument.ends_with(".json") || fs::is_regular_file(argument, ec)) {
    std::ifstream in(argument);
    if (!in) throw Error("cannot read spec file '" + argument + "'", "check the path");
    try {
      return TextureSpec::from_json(json::parse(in));
    } catch (const json::parse_error& e) {
      throw UsageError("spec file '" + argument + "' is not valid JSON: " + e.what(), "fix the file");
    }
  }
  TextureSpec spec;
  const auto colon = argument.find(':');
  spec.shader = trim(argument.substr(0, colon));
  if (spec.shader.empty()) throw UsageError("empty shader name in '" + argument + "'", "write NAME or NAME:key=value,...");
  if (colon == std::string::npos) return spec;
  for (const auto& item : split_top_level(argument.substr(colon + 1))) {
    if (item.empty()) continue;
    const auto eq = item.find('=');
    if (eq == std::string::npos)
      throw UsageError("'" + item + "' in '" + argument + "' is not key=value", "write NAME:key=value,...");
    const std::string key = trim(item.substr(0, eq));
    const json value = parse_inline_value(key, item.substr(eq + 1));
    if (key == "seed") {
      if (!value.is_number_integer() || value.get<int64_t>() < 0 || value.get<int64_t>() > 0xffffffffLL)
        throw UsageError("seed must be an integer in [0, 4294967295]", "write seed=7");
      spec.seed = static_cast<uint32_t>(value.get<int64_t>());
    } else {
      spec.params[key] = value;
    }
  }
  return spec;
}

std::vector<float> resolve(const ShaderDecl& decl, const TextureSpec& spec) {
  std::vector<float> packed = decl.default_packed();
  for (const auto& [name, value] : spec.params) {
    const ParamDecl* p = decl.find(name);
    if (!p) {
      std::string known;
      for (const auto& q : decl.params) known += (known.empty() ? "" : ", ") + q.name;
      throw UsageError("shader '" + decl.name + "' has no parameter '" + name + "'",
                       "its parameters are: " + known);
    }
    pack_value(decl, *p, value, packed.data() + p->offset);
  }
  return packed;
}

json param_to_json(const ParamDecl& p, const float* v) {
  switch (p.type) {
    case ParamType::Float: return v[0];
    case ParamType::Int: return static_cast<int64_t>(std::lround(v[0]));
    case ParamType::Bool: return v[0] >= 0.5f;
    case ParamType::Color: return json::array({v[0], v[1], v[2]});
    case ParamType::Enum: {
      const auto i = std::clamp<long>(std::lround(v[0]), 0, static_cast<long>(p.enum_values.size()) - 1);
      return p.enum_values[static_cast<size_t>(i)];
    }
  }
  return nullptr;
}

TextureSpec spec_from_packed(const ShaderDecl& decl, const std::vector<float>& packed, uint32_t seed) {
  TextureSpec spec;
  spec.shader = decl.name;
  spec.seed = seed;
  for (const auto& p : decl.params) spec.params[p.name] = param_to_json(p, packed.data() + p.offset);
  return spec;
}

}  // namespace proctex
