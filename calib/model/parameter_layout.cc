#include "calib/model/parameter_layout.h"

#include "calib/common/errors.h"
#include "calib/model/parameters.h"

namespace twin {

ParameterLayout::ParameterLayout(const RobotModel& model) {
  const KinematicModel& chain = model.chain;
  geometry_size_ = chain.num_parameters();
  const Eigen::VectorXd phi = GetParameters(chain);
  for (int i = 0; i < geometry_size_; ++i) {
    ParameterInfo p;
    p.name = ParameterName(chain.name, i);
    p.length = IsLengthParameter(i);
    p.unit = p.length ? "m" : "rad";
    p.block = "geometry";
    p.nominal = phi(i);
    p.scale = p.length ? kObservabilityCharacteristicLength : 1.0;
    info_.push_back(p);
  }
  blocks_.push_back({"geometry", 0, geometry_size_});
  int offset = geometry_size_;
  for (size_t t = 0; t < model.terms.size(); ++t) {
    const ErrorTerm& term = *model.terms[t];
    const std::string label = TermLabel(term.spec());
    for (size_t k = 0; k < term.parameters().size(); ++k) {
      const TermParameter& tp = term.parameters()[k];
      ParameterInfo p;
      p.name = tp.name;
      p.unit = tp.unit;
      p.block = label;
      p.nominal = model.term_values(offset - geometry_size_ + static_cast<int>(k));
      p.scale = tp.scale;
      p.term = static_cast<int>(t);
      info_.push_back(p);
    }
    blocks_.push_back({label, offset, static_cast<int>(term.parameters().size())});
    offset += static_cast<int>(term.parameters().size());
  }
}

int ParameterLayout::Find(const std::string& name) const {
  int found = -1;
  for (int i = 0; i < size() && found < 0; ++i) {
    if (info_[i].name == name) found = i;
  }
  // The names come from our own code (a fixed list built from this layout), not from a user.
  TWIN_REQUIRE(found >= 0, "\"" + name + "\" is no parameter of this model; its names have the "
                           "form <robot>.link<i>.<theta|d|a|alpha|beta> or belong to its error "
                           "terms (" + BlockNames() + ")");
  return found;
}

std::string ParameterLayout::BlockNames() const {
  std::string out;
  for (const ParameterBlock& b : blocks_) out += (out.empty() ? "" : ", ") + b.name;
  return out;
}

std::vector<std::string> ParameterLayout::names() const {
  std::vector<std::string> out;
  for (const ParameterInfo& p : info_) out.push_back(p.name);
  return out;
}

Eigen::VectorXd ParameterLayout::scales() const {
  Eigen::VectorXd s(size());
  for (int i = 0; i < size(); ++i) s(i) = info_[i].scale;
  return s;
}

}  // namespace twin
