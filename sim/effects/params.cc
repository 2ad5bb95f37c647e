#include "sim/effects/params.h"

#include <cassert>
#include <cmath>
#include <cstdio>
#include <utility>

#include "calib/common/errors.h"

namespace twin::effects {

bool Range::Contains(double value) const {
  if (!std::isfinite(value)) return false;
  if (lower_open ? !(value > lower) : !(value >= lower)) return false;
  if (upper_open ? !(value < upper) : !(value <= upper)) return false;
  return !integer || value == std::floor(value);
}

std::string Range::Describe() const {
  std::string text = integer ? "a whole number" : "a finite number";
  const bool has_lower = std::isfinite(lower), has_upper = std::isfinite(upper);
  if (has_lower && has_upper && !lower_open && !upper_open) {
    return text + " in [" + FormatValue(lower) + ", " + FormatValue(upper) + "]";
  }
  if (has_lower) text += std::string(lower_open ? " > " : " >= ") + FormatValue(lower);
  if (has_lower && has_upper) text += " and";
  if (has_upper) text += std::string(upper_open ? " < " : " <= ") + FormatValue(upper);
  return text;
}

Range AnyFinite() { return Range{}; }

Range Positive() {
  Range r;
  r.lower = 0.0;
  r.lower_open = true;
  return r;
}

Range NonNegative() {
  Range r;
  r.lower = 0.0;
  return r;
}

Range Between(double lower, double upper) {
  Range r;
  r.lower = lower;
  r.upper = upper;
  return r;
}

Range PositiveUpTo(double upper) {
  Range r = Between(0.0, upper);
  r.lower_open = true;
  return r;
}

Range IntegerAtLeast(double lower) {
  Range r;
  r.lower = lower;
  r.integer = true;
  return r;
}

ParamDef Required(std::string key, double to_si, Range range) {
  return ParamDef{std::move(key), to_si, true, 0.0, range};
}

ParamDef Optional(std::string key, double to_si, double default_value, Range range) {
  assert(range.Contains(default_value));
  return ParamDef{std::move(key), to_si, false, default_value, range};
}

Params::Params(const EffectSpec& spec, std::vector<ParamDef> defs, const std::string& allowed)
    : spec_(spec), defs_(std::move(defs)) {
  std::string allowed_text = allowed;
  if (allowed_text.empty()) {
    for (const ParamDef& def : defs_) {
      allowed_text += (allowed_text.empty() ? "" : ", ") + def.key;
    }
    if (allowed_text.empty()) allowed_text = "none";
  }
  for (const auto& [key, value] : spec_.params) {
    const ParamDef* def = nullptr;
    for (const ParamDef& d : defs_) {
      if (d.key == key) def = &d;
    }
    if (def == nullptr) {
      throw InputError(spec_.where, EffectLabel(spec_) + "unknown parameter \"" + key +
                                        "\"; allowed: " + allowed_text);
    }
    if (!def->range.Contains(value)) {
      throw InputError(spec_.where, EffectLabel(spec_) + "parameter " + key + " = " +
                                        FormatValue(value) + ", expected " +
                                        def->range.Describe());
    }
  }
  for (const ParamDef& def : defs_) {
    if (def.required && spec_.params.count(def.key) == 0) {
      throw InputError(spec_.where, EffectLabel(spec_) + "missing required parameter \"" +
                                        def.key + "\" (" + def.range.Describe() + ")");
    }
  }
}

const ParamDef& Params::Def(const std::string& key) const {
  for (const ParamDef& def : defs_) {
    if (def.key == key) return def;
  }
  assert(false && "parameter key not in the effect's table");
  return defs_.front();
}

double Params::Get(const std::string& key) const {
  const ParamDef& def = Def(key);
  const auto it = spec_.params.find(key);
  return (it == spec_.params.end() ? def.default_value : it->second) * def.to_si;
}

bool Params::Given(const std::string& key) const {
  Def(key);  // asserts the key is declared
  return spec_.params.count(key) != 0;
}

void RequireAllJoints(const EffectSpec& spec, const std::string& why) {
  if (spec.joint != -1) {
    throw InputError(spec.where, EffectLabel(spec) + "joint = " + std::to_string(spec.joint) +
                                     ", expected -1 (" + why + ")");
  }
}

void RequireAllRobots(const EffectSpec& spec, const std::string& why) {
  if (spec.robot != -1) {
    throw InputError(spec.where, EffectLabel(spec) + "robot = " + std::to_string(spec.robot) +
                                     ", expected -1 (" + why + ")");
  }
}

std::string EffectLabel(const EffectSpec& spec) { return "effect \"" + spec.type + "\": "; }

std::string FormatValue(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.10g", value);
  return buffer;
}

}  // namespace twin::effects
