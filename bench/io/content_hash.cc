#include "bench/io/content_hash.h"

#include <cstdio>

#include "bench/io/yaml_util.h"

namespace twin {

std::uint64_t Fnv1a64(const std::string& text) {
  std::uint64_t h = 14695981039346656037ull;  // FNV offset basis
  for (const unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ull;  // FNV prime
  }
  return h;
}

std::string HashHex(std::uint64_t hash) {
  char buf[17];
  std::snprintf(buf, sizeof(buf), "%016llx", static_cast<unsigned long long>(hash));
  return buf;
}

std::string ScenarioHash(const Scenario& scenario) {
  // Each part with its length in front, so that no two file sets give the same byte stream.
  std::string all;
  auto add = [&](const std::string& text) {
    all += std::to_string(text.size());
    all += ':';
    all += text;
  };
  add(ReadTextFile(scenario.path));
  for (const std::string& model : scenario.model_paths) add(ReadTextFile(model));
  return HashHex(Fnv1a64(all));
}

}  // namespace twin
