#include "cairn/io/transform_file.hpp"

#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

#include "cairn/io/compressed_file.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/text_reader.hpp"
#include "cairn/io/trajectory.hpp"

namespace cairn::io {
namespace {

/// Every number of the text, comment lines skipped; ParseError at the first token that is not a
/// finite number.
std::vector<double> numbers_of(const std::string& path, const std::string& contents) {
  std::vector<double> values;
  TextReader reader(path, contents);
  while (reader.next_line()) {
    if (is_blank_or_comment(reader.line())) continue;
    for (const std::string_view token : split_whitespace(reader.line())) {
      const std::string text(token);
      char* end = nullptr;
      const double value = std::strtod(text.c_str(), &end);
      if (end != text.c_str() + text.size() || !std::isfinite(value)) {
        throw ParseError(path, reader.line_number(), "expected a finite number, found '" + text + "'");
      }
      if (values.size() == 16) throw ParseError(path, reader.line_number(), "more than 16 numbers: expected 12 or 16");
      values.push_back(value);
    }
  }
  return values;
}

}  // namespace

core::SE3 parse_transform(const std::string& path, const std::string& contents) {
  const std::vector<double> v = numbers_of(path, contents);
  if (v.size() != 12 && v.size() != 16) {
    throw ParseError(path, 0, "expected 12 numbers (3 x 4) or 16 (4 x 4) of a rigid transform, found " + std::to_string(v.size()));
  }
  Matrix4 T = Matrix4::Identity();
  for (std::size_t k = 0; k < v.size(); ++k) T(static_cast<Eigen::Index>(k / 4), static_cast<Eigen::Index>(k % 4)) = v[k];
  if (v.size() == 16 && !(T.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).isZero(1e-9)) {
    throw ParseError(path, 0, "the last row of the 4 x 4 matrix must be 0 0 0 1");
  }
  const Matrix3 R = T.topLeftCorner<3, 3>();
  const double error = (R.transpose() * R - Matrix3::Identity()).cwiseAbs().maxCoeff();
  if (!(error <= kMaxRotationOrthonormalityError) || !(R.determinant() > 0.0)) {
    throw ParseError(path, 0, "the 3 x 3 block is not a rotation (|R^T R - I| = " + std::to_string(error) + ")");
  }
  return core::SE3::from_matrix(T);
}

core::SE3 read_transform(const std::string& path) { return parse_transform(path, read_maybe_compressed(path, 1 << 20)); }

}  // namespace cairn::io
