#include "calib/cell/cell.h"

namespace twin {

const char* ToString(MoveStatus status) {
  switch (status) {
    case MoveStatus::kSettled: return "settled";
    case MoveStatus::kCollision: return "collision";
    case MoveStatus::kNotSettled: return "not_settled";
    case MoveStatus::kOutOfLimits: return "out_of_limits";
    case MoveStatus::kInvalidInput: return "invalid_input";
  }
  return "unknown";
}

}  // namespace twin
