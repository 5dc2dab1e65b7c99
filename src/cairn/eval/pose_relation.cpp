#include "cairn/eval/pose_relation.hpp"

#include <cmath>
#include <numbers>

#include "cairn/core/so3.hpp"

namespace cairn::eval {

std::string_view to_string(PoseRelation relation) {
  switch (relation) {
    case PoseRelation::kTranslationPart: return "trans_part";
    case PoseRelation::kRotationAngleRad: return "angle_rad";
    case PoseRelation::kRotationAngleDeg: return "angle_deg";
    case PoseRelation::kRotationPart: return "rot_part";
    case PoseRelation::kFullTransformation: return "full";
  }
  return "trans_part";
}

std::optional<PoseRelation> pose_relation_from_name(std::string_view name) {
  for (PoseRelation r : {PoseRelation::kTranslationPart, PoseRelation::kRotationAngleRad,
                         PoseRelation::kRotationAngleDeg, PoseRelation::kRotationPart,
                         PoseRelation::kFullTransformation}) {
    if (name == to_string(r)) return r;
  }
  return std::nullopt;
}

std::string_view unit_of(PoseRelation relation) {
  switch (relation) {
    case PoseRelation::kTranslationPart: return "m";
    case PoseRelation::kRotationAngleRad: return "rad";
    case PoseRelation::kRotationAngleDeg: return "deg";
    case PoseRelation::kRotationPart:
    case PoseRelation::kFullTransformation: return "";
  }
  return "";
}

std::string_view describe(PoseRelation relation) {
  switch (relation) {
    case PoseRelation::kTranslationPart: return "translation part";
    case PoseRelation::kRotationAngleRad: return "rotation angle in radians";
    case PoseRelation::kRotationAngleDeg: return "rotation angle in degrees";
    case PoseRelation::kRotationPart: return "rotation part";
    case PoseRelation::kFullTransformation: return "full transformation";
  }
  return "";
}

double pose_error(const Matrix4& E, PoseRelation relation) {
  switch (relation) {
    case PoseRelation::kTranslationPart: return E.topRightCorner<3, 1>().norm();
    case PoseRelation::kRotationAngleRad: return core::SO3::from_matrix(E.topLeftCorner<3, 3>()).angle();
    case PoseRelation::kRotationAngleDeg:
      return core::SO3::from_matrix(E.topLeftCorner<3, 3>()).angle() * 180.0 / std::numbers::pi;
    case PoseRelation::kRotationPart: return (E.topLeftCorner<3, 3>() - Matrix3::Identity()).norm();
    case PoseRelation::kFullTransformation: return (E - Matrix4::Identity()).norm();
  }
  return 0.0;
}

}  // namespace cairn::eval
