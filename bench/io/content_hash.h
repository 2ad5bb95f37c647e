// Content hashes that name things by what they hold: a study's scenario (its file and the
// model files it loads), a cached plan's inputs. FNV-1a, 64 bits: an identity check against
// mix-ups (another scenario, an edited file), not a cryptographic digest.
#pragma once

#include <cstdint>
#include <string>

#include "bench/io/scenario.h"

namespace twin {

/// FNV-1a 64-bit hash of `text`.
std::uint64_t Fnv1a64(const std::string& text);

/// 16 lower-case hex digits of a hash.
std::string HashHex(std::uint64_t hash);

/// The hash of a scenario as loaded: its file's bytes and those of every model file it names
/// (a model edited in place changes it; moving the files does not). 16 hex digits. Throws
/// InputError when a file cannot be read.
std::string ScenarioHash(const Scenario& scenario);

}  // namespace twin
