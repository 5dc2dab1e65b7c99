#pragma once
/// \file
/// Which part of an error pose E a metric measures, as evo's PoseRelation
/// (evo/core/metrics.py, APE.process_data and RPE.process_data):
///
/// | relation              | error of one pair               | unit    |
/// |-----------------------|---------------------------------|---------|
/// | kTranslationPart      | |t(E)|                          | m       |
/// | kRotationAngleRad     | |angle(R(E))| (log map angle)   | rad     |
/// | kRotationAngleDeg     | the same in degrees             | deg     |
/// | kRotationPart         | ||R(E) - I||_F (Frobenius)      | none    |
/// | kFullTransformation   | ||E - I_4x4||_F                 | none    |
///
/// APE: E = T_est^-1 T_ref (evo ape_base = relative_se3(x_t, x_t_star)); the translation part
/// is evo's shortcut |p_est - p_ref|, which is what evo computes (not |t(E)|, which would
/// rotate the difference into the estimate's frame: the norm is the same).
/// RPE: E = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j) with Q the reference and P the estimate (evo rpe_base,
/// after Sturm et al., IROS 2012, eq. 1).

#include <optional>
#include <string_view>

#include "cairn/core/types.hpp"

namespace cairn::eval {

enum class PoseRelation {
  kTranslationPart,
  kRotationAngleRad,
  kRotationAngleDeg,
  kRotationPart,
  kFullTransformation,
};

/// "trans_part", "angle_rad", "angle_deg", "rot_part", "full": evo's `-r` names.
std::string_view to_string(PoseRelation relation);
std::optional<PoseRelation> pose_relation_from_name(std::string_view name);
/// "m", "rad", "deg" or "" (dimension-less), as evo's Unit.
std::string_view unit_of(PoseRelation relation);
/// evo's wording: "translation part", "rotation angle in degrees", ...
std::string_view describe(PoseRelation relation);

/// The error of one error pose E under `relation` (table above). The angle is that of the
/// rotation nearest to E's 3x3 block (evo: scipy Rotation.from_matrix(...).as_rotvec()).
double pose_error(const Matrix4& E, PoseRelation relation);

}  // namespace cairn::eval
