#include "shaders/shader.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <regex>
#include <set>
#include <sstream>

#include "core/error.h"
#include "core/hash.h"

namespace proctex {
namespace {

struct LineError {
  const std::string& path;
  int line;
  [[noreturn]] void fail(const std::string& what) const {
    throw Error(path + ":" + std::to_string(line) + ": " + what,
                "fix the @param/@shader declaration (format: see shaders/shader.h or docs/shaders.md)");
  }
};

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  const auto e = s.find_last_not_of(" \t\r");
  return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
}

float parse_number(const std::string& text, const LineError& at, const char* what) {
  const std::string t = trim(text);
  char* end = nullptr;
  const float v = std::strtof(t.c_str(), &end);
  if (t.empty() || end != t.c_str() + t.size() || !std::isfinite(v))
    at.fail(std::string("cannot read ") + what + " '" + t + "' as a number");
  return v;
}

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(trim(item));
  return out;
}

// A parameter or enum value name, as the generated OpenCL struct and constants need it.
bool is_identifier(const std::string& text) {
  static const std::regex identifier(R"([A-Za-z_]\w*)");
  return std::regex_match(text, identifier);
}

// Flags and help text that follow the default/range: `log fixed "help"`.
void parse_tail(const std::string& tail, ParamDecl& p, const LineError& at) {
  static const std::regex tail_re(R"(^\s*((?:[a-z]+(?:=[^\s"]+)?\s+)*)\"(.*)\"\s*$)");
  std::smatch m;
  if (!std::regex_match(tail, m, tail_re)) at.fail("expected flags then a \"quoted help text\"");
  std::stringstream flags(m[1].str());
  std::string flag;
  while (flags >> flag) {
    if (flag == "log") p.scale = Scale::Log;
    else if (flag == "linear") p.scale = Scale::Linear;
    else if (flag == "fixed") p.searchable = false;
    else if (flag == "search") p.searchable = true;
    else if (flag.starts_with("period=")) {
      // period=P or period=P/COUNT (checked against the other declarations in parse_shader)
      const std::string expr = flag.substr(7);
      const auto slash = expr.find('/');
      p.period = parse_number(expr.substr(0, slash), at, "period");
      if (slash != std::string::npos) {
        p.period_per = trim(expr.substr(slash + 1));
        if (!is_identifier(p.period_per))
          at.fail("period '" + expr + "': expected a number or NUMBER/COUNT_PARAMETER");
      }
      if (!(p.period > 0.0f)) at.fail("period of '" + p.name + "' must be positive");
    } else if (flag.starts_with("exchange=")) {
      // exchange=A/B (checked against the other declarations in parse_shader)
      const std::string expr = flag.substr(9);
      const auto slash = expr.find('/');
      if (slash == std::string::npos || !is_identifier(expr.substr(0, slash)) || !is_identifier(expr.substr(slash + 1)))
        at.fail("exchange '" + expr + "': expected two parameter names, A/B");
      p.exchange = {expr.substr(0, slash), expr.substr(slash + 1)};
    } else if (flag.starts_with("needs=")) {
      // needs=G (checked against the other declarations in parse_shader)
      p.needs = flag.substr(6);
      if (!is_identifier(p.needs))
        at.fail("needs '" + p.needs + "': expected a parameter name");
    } else
      at.fail("unknown flag '" + flag +
              "' (known: log, linear, fixed, search, period=P[/COUNT], exchange=A/B, needs=G)");
  }
  p.help = m[2].str();
  if (p.help.empty()) at.fail("parameter '" + p.name + "' needs a one-line help text");
}

void check_range(ParamDecl& p, const LineError& at) {
  if (!(p.min < p.max)) at.fail("range of '" + p.name + "' must have min < max");
  for (float v : p.default_value)
    if (v < p.min || v > p.max) at.fail("default of '" + p.name + "' lies outside its range");
  if (p.scale == Scale::Log && p.min <= 0.0f)
    at.fail("log-scaled '" + p.name + "' needs a positive minimum");
  if (p.type == ParamType::Int &&
      (p.min != std::round(p.min) || p.max != std::round(p.max) ||
       p.default_value[0] != std::round(p.default_value[0])))
    at.fail("int parameter '" + p.name + "' needs integer default and range");
}

ParamDecl parse_param(const std::string& body, const LineError& at) {
  static const std::regex head_re(R"(^\s*(\w+)\s+([A-Za-z_]\w*)\s*=\s*(.*)$)");
  std::smatch m;
  if (!std::regex_match(body, m, head_re)) at.fail("expected '@param TYPE NAME = DEFAULT ...'");
  ParamDecl p;
  p.name = m[2].str();
  p.line = at.line;
  const std::string type = m[1].str();
  const std::string rest = m[3].str();
  std::smatch r;
  if (type == "float" || type == "int") {
    static const std::regex re(R"(^([^\s\[]+)\s*\[([^,\]]+),([^\]]+)\](.*)$)");
    if (!std::regex_match(rest, r, re)) at.fail("expected 'DEFAULT [MIN, MAX]' for " + type + " '" + p.name + "'");
    p.type = type == "float" ? ParamType::Float : ParamType::Int;
    p.default_value = {parse_number(r[1].str(), at, "default")};
    p.min = parse_number(r[2].str(), at, "minimum");
    p.max = parse_number(r[3].str(), at, "maximum");
    parse_tail(r[4].str(), p, at);
  } else if (type == "color") {
    static const std::regex re(R"(^\(([^)]*)\)\s*(?:\[([^,\]]+),([^\]]+)\])?(.*)$)");
    if (!std::regex_match(rest, r, re)) at.fail("expected '(R, G, B)' default for colour '" + p.name + "'");
    p.type = ParamType::Color;
    const auto parts = split_list(r[1].str());
    if (parts.size() != 3) at.fail("colour '" + p.name + "' needs three components");
    for (const auto& c : parts) p.default_value.push_back(parse_number(c, at, "colour component"));
    if (r[2].matched) {
      p.min = parse_number(r[2].str(), at, "minimum");
      p.max = parse_number(r[3].str(), at, "maximum");
    }
    parse_tail(r[4].str(), p, at);
  } else if (type == "bool") {
    static const std::regex re(R"(^(true|false)\b(.*)$)");
    if (!std::regex_match(rest, r, re)) at.fail("bool '" + p.name + "' needs default true or false");
    p.type = ParamType::Bool;
    p.default_value = {r[1].str() == "true" ? 1.0f : 0.0f};
    parse_tail(r[2].str(), p, at);
  } else if (type == "enum") {
    static const std::regex re(R"(^(\w+)\s*\{([^}]*)\}(.*)$)");
    if (!std::regex_match(rest, r, re)) at.fail("expected 'DEFAULT {a, b, ...}' for enum '" + p.name + "'");
    p.type = ParamType::Enum;
    p.enum_values = split_list(r[2].str());
    if (p.enum_values.size() < 2) at.fail("enum '" + p.name + "' needs at least two values");
    std::set<std::string> seen;
    for (const auto& v : p.enum_values) {
      if (!is_identifier(v)) at.fail("enum value '" + v + "' is not an identifier");
      if (!seen.insert(v).second) at.fail("enum value '" + v + "' repeats");
    }
    const auto it = std::find(p.enum_values.begin(), p.enum_values.end(), r[1].str());
    if (it == p.enum_values.end()) at.fail("enum default '" + r[1].str() + "' is not one of its values");
    p.default_value = {static_cast<float>(it - p.enum_values.begin())};
    p.max = static_cast<float>(p.enum_values.size() - 1);
    parse_tail(r[3].str(), p, at);
  } else {
    at.fail("unknown parameter type '" + type + "' (float, int, bool, color, enum)");
  }
  if (p.type != ParamType::Bool) check_range(p, at);
  if (p.period > 0.0f && (p.type != ParamType::Float || p.scale != Scale::Linear))
    at.fail("period of '" + p.name + "': only a linear float parameter can be periodic");
  if (!p.exchange.empty() && (p.type != ParamType::Float || p.scale != Scale::Linear))
    at.fail("exchange of '" + p.name + "': only a linear float parameter can declare one");
  if (!p.needs.empty() && p.type != ParamType::Float && p.type != ParamType::Int)
    at.fail("needs of '" + p.name + "': only a float or int parameter can declare one");
  return p;
}

std::string file_stem(const std::string& path) {
  const auto slash = path.find_last_of('/');
  std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
  if (name.ends_with(".cl")) name.resize(name.size() - 3);
  return name;
}

std::string parent_name(const std::string& path) {
  const auto slash = path.find_last_of('/');
  if (slash == std::string::npos) return "user";
  const auto prev = path.find_last_of('/', slash - 1);
  return path.substr(prev == std::string::npos ? 0 : prev + 1,
                     slash - (prev == std::string::npos ? 0 : prev + 1));
}

}  // namespace

const char* to_string(ParamType type) {
  switch (type) {
    case ParamType::Float: return "float";
    case ParamType::Int: return "int";
    case ParamType::Bool: return "bool";
    case ParamType::Color: return "color";
    case ParamType::Enum: return "enum";
  }
  return "?";
}

const char* to_string(Scale scale) { return scale == Scale::Log ? "log" : "linear"; }

const ParamDecl* ShaderDecl::find(const std::string& param) const {
  for (const auto& p : params)
    if (p.name == param) return &p;
  return nullptr;
}

std::vector<float> ShaderDecl::default_packed() const {
  std::vector<float> packed(packed_size);
  for (const auto& p : params)
    std::copy(p.default_value.begin(), p.default_value.end(), packed.begin() + p.offset);
  return packed;
}

std::string stable_hash(const std::string& text) { return fnv1a_hex(text); }

double symmetry_period(const ShaderDecl& decl, const ParamDecl& p, const std::vector<float>& packed) {
  if (!(p.period > 0.0f)) return 0.0;
  if (p.period_per.empty()) return p.period;
  const ParamDecl* count = decl.find(p.period_per);
  if (!count || count->offset >= static_cast<int>(packed.size())) return 0.0;
  const double n = std::round(packed[count->offset]);
  return n >= 1.0 ? double(p.period) / n : 0.0;
}

std::vector<float> canonical_packed(const ShaderDecl& decl, std::vector<float> packed) {
  for (const auto& p : decl.params) {
    const double period = symmetry_period(decl, p, packed);
    if (period <= 0.0 || p.offset >= static_cast<int>(packed.size())) continue;
    float& v = packed[p.offset];
    double r = std::fmod(double(v) - p.min, period);
    if (r < 0) r += period;
    // A value a rounding error below a whole period reads as the period's start.
    if (period - r < 1e-6 * period) r = 0.0;
    v = static_cast<float>(std::clamp(p.min + r, double(p.min), double(p.max)));
  }
  // A parameter whose declared gate is off does nothing: it reads as its default (a grid without
  // minor lines has subdivisions 1, however many the search left at minor strength 0).
  for (const auto& p : decl.params) {
    const ParamDecl* gate = p.needs.empty() ? nullptr : decl.find(p.needs);
    if (!gate || gate->offset >= static_cast<int>(packed.size()) || p.offset >= static_cast<int>(packed.size())) continue;
    if (packed[gate->offset] <= gate->min) packed[p.offset] = p.default_value[0];
  }
  return packed;
}

double parameter_difference(const ShaderDecl& decl, const ParamDecl& p, float a, float b,
                            const std::vector<float>& packed) {
  const double d = std::fabs(double(a) - double(b));
  const double period = symmetry_period(decl, p, packed);
  if (period <= 0.0) return d;
  const double r = std::fmod(d, period);
  return std::min(r, period - r);
}

ShaderDecl parse_shader(const std::string& path, const std::string& source) {
  ShaderDecl decl;
  decl.path = path;
  decl.name = file_stem(path);
  decl.family = parent_name(path);
  decl.source = source;
  decl.source_hash = stable_hash(source);
  if (!std::regex_match(decl.name, std::regex(R"([a-z][a-z0-9_]*)")))
    throw Error(path + ": shader file name must be lower_case_with_underscores.cl",
                "rename the file");

  static const std::regex shader_re(R"(^\s*//\s*@shader\s+\"(.*)\"\s*$)");
  static const std::regex param_re(R"(^\s*//\s*@param\s+(.*)$)");
  static const std::regex stray_re(R"(^\s*//\s*@(\w+))");
  std::set<std::string> names;
  std::istringstream in(source);
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    const LineError at{path, number};
    std::smatch m;
    if (std::regex_match(line, m, shader_re)) {
      decl.help = m[1].str();
    } else if (std::regex_match(line, m, param_re)) {
      ParamDecl p = parse_param(m[1].str(), at);
      if (p.name == "seed") at.fail("'seed' is reserved: every shader receives the seed argument");
      if (!names.insert(p.name).second) at.fail("parameter '" + p.name + "' is declared twice");
      p.offset = decl.packed_size;
      decl.packed_size += p.width();
      decl.params.push_back(std::move(p));
    } else if (std::regex_search(line, m, stray_re)) {
      at.fail("unknown declaration '@" + m[1].str() + "' (known: @shader, @param)");
    }
  }
  for (const auto& p : decl.params) {
    if (p.exchange.empty()) continue;
    const LineError at{path, p.line};
    const ParamDecl* a = decl.find(p.exchange[0]);
    const ParamDecl* b = decl.find(p.exchange[1]);
    if (!a || !b || a == b || a == &p || b == &p || a->type != ParamType::Float || b->type != ParamType::Float)
      at.fail("exchange of '" + p.name + "': '" + p.exchange[0] + "' and '" + p.exchange[1] +
              "' must be two other float parameters here");
    if (a->min != b->min || a->max != b->max || a->scale != b->scale)
      at.fail("exchange of '" + p.name + "': '" + a->name + "' and '" + b->name + "' need the same range and scale");
  }
  for (const auto& p : decl.params) {
    if (p.needs.empty()) continue;
    const LineError at{path, p.line};
    const ParamDecl* gate = decl.find(p.needs);
    if (!gate || gate == &p || gate->type != ParamType::Float || gate->scale != Scale::Linear)
      at.fail("needs of '" + p.name + "': '" + p.needs + "' must be another linear float parameter here");
  }
  for (const auto& p : decl.params) {
    if (p.period_per.empty()) continue;
    const LineError at{path, p.line};
    const ParamDecl* count = decl.find(p.period_per);
    if (!count || count->type != ParamType::Int)
      at.fail("period of '" + p.name + "' is divided by '" + p.period_per + "', which is not an int parameter here");
    if (count->min < 1.0f) at.fail("period of '" + p.name + "' is divided by '" + p.period_per + "', whose range includes " + std::to_string(int(count->min)) + " (needs >= 1)");
  }
  if (decl.help.empty())
    throw Error(path + ":1: missing '// @shader \"one-line description\"' line",
                "every shader file starts with its @shader line");
  if (source.find("shade(") == std::string::npos)
    throw Error(path + ": no 'float3 shade(float2 p, float fw, uint seed, const Params P)' function",
                "define the shade function the generated kernel calls");
  return decl;
}

}  // namespace proctex
