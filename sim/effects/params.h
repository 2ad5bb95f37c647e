// Checking an effect's parameters (spec.params) against a declared table: every effect lists
// its keys once, with the unit conversion to SI, required or default, and the allowed range;
// Params then rejects unknown keys, missing required keys and bad values with an InputError
// naming spec.where, the effect type, the key and what was expected.
#pragma once

#include <limits>
#include <map>
#include <string>
#include <vector>

#include "calib/common/frames.h"
#include "sim/world/twin_spec.h"

namespace twin::effects {

/// Factors from a key's unit to SI (the key's suffix names the unit).
constexpr double kUnitless = 1.0;          ///< no conversion (K, counts, grey levels, N m/rad)
constexpr double kMillimetre = 1e-3;       ///< "_mm" keys to m
constexpr double kDegree = kPi / 180.0;    ///< "_deg" keys to rad

/// The values a parameter may take, in the key's own unit (the user's numbers).
struct Range {
  double lower = -std::numeric_limits<double>::infinity();  ///< bound, in the key's unit
  double upper = std::numeric_limits<double>::infinity();   ///< bound, in the key's unit
  bool lower_open = false;   ///< true: value > lower, false: value >= lower
  bool upper_open = false;   ///< true: value < upper, false: value <= upper
  bool integer = false;      ///< value must be a whole number

  /// True if `value` is finite and inside the range.
  bool Contains(double value) const;
  /// What is expected, for messages (e.g. "a finite number > 0").
  std::string Describe() const;
};

Range AnyFinite();                              ///< any finite number
Range Positive();                               ///< > 0
Range NonNegative();                            ///< >= 0
Range Between(double lower, double upper);      ///< in [lower, upper]
Range PositiveUpTo(double upper);               ///< in (0, upper]
Range IntegerAtLeast(double lower);             ///< whole number >= lower

/// One accepted key of an effect.
struct ParamDef {
  std::string key;              ///< with its unit suffix, e.g. "width_deg"
  double to_si = kUnitless;     ///< factor from the key's unit to SI
  bool required = true;         ///< false: `default_value` when absent
  double default_value = 0.0;   ///< in the key's unit
  Range range;                  ///< allowed values, in the key's unit
};

/// A required key.
ParamDef Required(std::string key, double to_si, Range range);
/// An optional key with a default (in the key's unit).
ParamDef Optional(std::string key, double to_si, double default_value, Range range);

/// An effect's parameters checked against its table; values are returned in SI.
class Params {
 public:
  /// Checks spec.params against `defs`. `allowed` describes the accepted keys in the
  /// unknown-key message; empty means the list of def keys. Throws InputError naming
  /// spec.where and spec.type for an unknown key (listing the allowed ones), a missing required
  /// key, or a value outside its range (naming the key, the value and the expected range).
  Params(const EffectSpec& spec, std::vector<ParamDef> defs, const std::string& allowed = "");

  /// The value of `key` in SI units (its default if optional and absent). `key` must be in
  /// the table (asserted: a wrong key here is our bug).
  double Get(const std::string& key) const;
  /// True if the spec gave `key` explicitly.
  bool Given(const std::string& key) const;

 private:
  const ParamDef& Def(const std::string& key) const;

  EffectSpec spec_;  // a copy, so Params may outlive the caller's spec
  std::vector<ParamDef> defs_;
};

/// Throws InputError naming spec.where unless spec.joint is -1 (effects on a whole robot or on
/// the image); `why` says what the effect acts on.
void RequireAllJoints(const EffectSpec& spec, const std::string& why);
/// Throws InputError naming spec.where unless spec.robot is -1 (effects not tied to a robot).
void RequireAllRobots(const EffectSpec& spec, const std::string& why);

/// "effect \"<type>\": " prefix of every message about an effect.
std::string EffectLabel(const EffectSpec& spec);
/// `value` formatted for messages (shortest round-trip-ish form, e.g. "-0.1", "1e-05").
std::string FormatValue(double value);

}  // namespace twin::effects
