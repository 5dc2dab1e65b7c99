#include "synthetic_world.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <future>
#include <limits>

namespace cairn::test {
namespace {

constexpr double kPi = 3.14159265358979323846;

// splitmix64's finaliser (Steele, Lea & Flood, OOPSLA 2014): a cheap, well-mixed hash.
std::uint64_t mix(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// 16 bits of h starting at `shift`, as a number in [0, 1).
double unit(std::uint64_t h, int shift) { return static_cast<double>((h >> shift) & 0xFFFFu) / 65536.0; }

// The procedural texture, cell by cell: a "Mondrian" of 0.2 m cells, each a random background
// grey with three random rectangles or discs of random grey on it (later shapes cover earlier
// ones). A cell's shapes are kept, since neighbouring samples mostly fall into the same cell.
class TextureCell {
 public:
  double value(std::uint64_t seed, double u, double v) {
    const double su = u / kCell, sv = v / kCell;
    const std::int64_t i = floor_to_int(su), j = floor_to_int(sv);
    if (!valid_ || seed != seed_ || i != i_ || j != j_) build(seed, i, j);
    const double x = su - static_cast<double>(i), y = sv - static_cast<double>(j);
    double value = background_;
    for (const Shape& s : shapes_) {
      const double dx = x - s.centre_x, dy = y - s.centre_y;
      if (s.rectangle ? (std::abs(dx) < s.half_x && std::abs(dy) < s.half_y) : (dx * dx + dy * dy < s.half_x * s.half_x)) value = s.grey;
    }
    return value;
  }

 private:
  static constexpr double kCell = 0.2;
  // floor() for the texture's range (|x| < 2^62); std::floor is a call or a slow bit trick
  // without SSE4.1, and this is the renderer's innermost loop.
  static std::int64_t floor_to_int(double x) {
    const auto i = static_cast<std::int64_t>(x);
    return x < static_cast<double>(i) ? i - 1 : i;
  }
  struct Shape {
    double centre_x, centre_y, half_x, half_y, grey;
    bool rectangle;
  };

  void build(std::uint64_t seed, std::int64_t i, std::int64_t j) {
    valid_ = true;
    seed_ = seed;
    i_ = i;
    j_ = j;
    const std::uint64_t h = mix(mix(seed) ^ mix(static_cast<std::uint64_t>(i) * 0x9E3779B97F4A7C15ull +
                                                static_cast<std::uint64_t>(j) * 0xC2B2AE3D27D4EB4Full + 0x165667B19E3779F9ull));
    background_ = 25.0 + 205.0 * unit(h, 0);
    for (std::size_t k = 0; k < shapes_.size(); ++k) {
      const std::uint64_t s = mix(h + k + 1);
      Shape& shape = shapes_[k];
      shape.centre_x = 0.1 + 0.8 * unit(s, 0);
      shape.centre_y = 0.1 + 0.8 * unit(s, 16);
      shape.half_x = 0.06 + 0.3 * unit(s, 32);
      shape.half_y = 0.06 + 0.3 * unit(s, 48);
      shape.grey = 15.0 + 225.0 * unit(h, 16 * static_cast<int>(k + 1));
      shape.rectangle = (s & 1u) != 0;
    }
  }

  bool valid_ = false;
  std::uint64_t seed_ = 0;
  std::int64_t i_ = 0, j_ = 0;
  double background_ = 0.0;
  std::array<Shape, 3> shapes_{};
};

// The two in-plane axes of a surface normal to `axis`.
int axis_u(int axis) { return axis == 0 ? 2 : 0; }
int axis_v(int axis) { return axis == 1 ? 2 : 1; }

// A surface as the ray caster wants it.
struct Plane {
  int axis, a, b;
  double position, a_low, a_high, b_low, b_high;
  double origin_a, origin_b;
  std::uint64_t seed;
  bool textured;
  double grey;
};

std::vector<Plane> planes_of(const std::vector<Surface>& surfaces) {
  std::vector<Plane> planes;
  planes.reserve(surfaces.size());
  for (const Surface& s : surfaces) {
    Plane p{};
    p.axis = s.normal_axis;
    p.a = axis_u(s.normal_axis);
    p.b = axis_v(s.normal_axis);
    p.position = s.lower[p.axis];
    p.a_low = std::min(s.lower[p.a], s.upper[p.a]);
    p.a_high = std::max(s.lower[p.a], s.upper[p.a]);
    p.b_low = std::min(s.lower[p.b], s.upper[p.b]);
    p.b_high = std::max(s.lower[p.b], s.upper[p.b]);
    p.origin_a = s.texture_origin[p.a];
    p.origin_b = s.texture_origin[p.b];
    p.seed = s.texture.seed;
    p.textured = s.texture.textured;
    p.grey = s.texture.grey;
    planes.push_back(p);
  }
  return planes;
}

// The surfaces that can appear in the camera's view: a rectangle whose four corners all lie
// outside one of the frustum's four side planes (or behind the camera) cannot.
std::vector<Plane> planes_in_view(const std::vector<Surface>& surfaces, const core::SE3& T_world_camera, const StereoCamera& camera) {
  const core::SE3 T_camera_world = T_world_camera.inverse();
  // Pixel bounds of the image as slopes x/z and y/z, half a pixel of margin.
  const double x_low = (-0.5 - camera.cx) / camera.fx, x_high = (static_cast<double>(camera.width) - 0.5 - camera.cx) / camera.fx;
  const double y_low = (-0.5 - camera.cy) / camera.fy, y_high = (static_cast<double>(camera.height) - 0.5 - camera.cy) / camera.fy;
  std::vector<Surface> visible;
  for (const Surface& s : surfaces) {
    const int a = axis_u(s.normal_axis), b = axis_v(s.normal_axis);
    std::array<Eigen::Vector3d, 4> corners;
    for (int c = 0; c < 4; ++c) {
      Eigen::Vector3d p = s.lower;
      p[a] = (c & 1) ? s.upper[a] : s.lower[a];
      p[b] = (c & 2) ? s.upper[b] : s.lower[b];
      corners[static_cast<std::size_t>(c)] = T_camera_world * p;
    }
    auto all = [&](auto&& outside) {
      for (const Eigen::Vector3d& p : corners) {
        if (!outside(p)) return false;
      }
      return true;
    };
    if (all([](const Eigen::Vector3d& p) { return p.z() <= 0.0; }) ||
        all([&](const Eigen::Vector3d& p) { return p.x() < x_low * p.z(); }) ||
        all([&](const Eigen::Vector3d& p) { return p.x() > x_high * p.z(); }) ||
        all([&](const Eigen::Vector3d& p) { return p.y() < y_low * p.z(); }) ||
        all([&](const Eigen::Vector3d& p) { return p.y() > y_high * p.z(); })) {
      continue;
    }
    visible.push_back(s);
  }
  return planes_of(visible);
}

// The nearest plane hit by the ray o + t d (t > 0), -1 for none. `first` (a plane index or -1)
// is tried first: neighbouring pixels mostly hit the same plane, and a near hit found early
// lets the others be rejected without a division.
int nearest_hit(const std::vector<Plane>& planes, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double* t_out, int first = -1) {
  int best = -1;
  double best_t = std::numeric_limits<double>::infinity();
  auto test = [&](std::size_t i) {
    const Plane& p = planes[i];
    const double da = d[p.axis];
    const double num = p.position - o[p.axis];
    // t = num / da in (1e-6, best_t), without dividing.
    if (da > 1e-12) {
      if (num <= 1e-6 * da || num >= best_t * da) return;
    } else if (da < -1e-12) {
      if (num >= 1e-6 * da || num <= best_t * da) return;
    } else {
      return;
    }
    const double t = num / da;
    const double a = o[p.a] + t * d[p.a];
    if (a < p.a_low || a > p.a_high) return;
    const double b = o[p.b] + t * d[p.b];
    if (b < p.b_low || b > p.b_high) return;
    best = static_cast<int>(i);
    best_t = t;
  };
  if (first >= 0) test(static_cast<std::size_t>(first));
  for (std::size_t i = 0; i < planes.size(); ++i) {
    if (static_cast<int>(i) != first) test(i);
  }
  *t_out = best_t;
  return best;
}

// The texture of plane p where the ray (o, d) meets its plane; `fallback` when it does not.
double shade(const Plane& p, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double fallback, TextureCell& cell) {
  if (!p.textured) return p.grey;
  const double da = d[p.axis];
  if (std::abs(da) < 1e-12) return fallback;
  const double t = (p.position - o[p.axis]) / da;
  if (t <= 0.0) return fallback;
  return cell.value(p.seed, o[p.a] + t * d[p.a] - p.origin_a, o[p.b] + t * d[p.b] - p.origin_b);
}

template <typename PixelFunction>
void for_each_pixel(const core::SE3& T_world_camera, const StereoCamera& camera, PixelFunction&& f) {
  const Eigen::Matrix3d R = T_world_camera.rotation_matrix();
  const Eigen::Vector3d o = T_world_camera.translation();
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      f(u, v, o, R);
    }
  }
}

Eigen::Vector3d ray(const Eigen::Matrix3d& R, const StereoCamera& camera, double u, double v) {
  return R * Eigen::Vector3d((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0);
}

}  // namespace

io::CameraCalibration StereoCamera::calibration() const {
  io::CameraCalibration c;
  c.fx = fx;
  c.fy = fy;
  c.cx = cx;
  c.cy = cy;
  c.width = width;
  c.height = height;
  c.baseline_m = baseline_m;
  c.depth_units_per_m = depth_units_per_m;
  c.virtual_baseline_m = baseline_m;
  return c;
}

double texture_value(std::uint64_t seed, double u, double v) {
  TextureCell cell;
  return cell.value(seed, u, v);
}

void SyntheticWorld::add_wall(int normal_axis, const Eigen::Vector3d& lower, const Eigen::Vector3d& upper,
                              const SurfaceTexture& texture, const Eigen::Vector3d& texture_origin,
                              const Eigen::Vector3d* opening_lower, const Eigen::Vector3d* opening_upper) {
  Surface s;
  s.normal_axis = normal_axis;
  s.texture = texture;
  s.texture_origin = texture_origin;
  if (opening_lower == nullptr || opening_upper == nullptr) {
    s.lower = lower;
    s.upper = upper;
    surfaces_.push_back(s);
    return;
  }
  // Up to four pieces around the opening: below and above it in a (full width of the wall),
  // then left and right of it in b (the opening's extent in a).
  const int a = axis_u(normal_axis), b = axis_v(normal_axis);
  const double ol_a = std::max((*opening_lower)[a], lower[a]), ou_a = std::min((*opening_upper)[a], upper[a]);
  const double ol_b = std::max((*opening_lower)[b], lower[b]), ou_b = std::min((*opening_upper)[b], upper[b]);
  auto piece = [&](double a0, double a1, double b0, double b1) {
    if (a1 - a0 <= 1e-9 || b1 - b0 <= 1e-9) return;
    s.lower = lower;
    s.upper = lower;
    s.lower[a] = a0;
    s.upper[a] = a1;
    s.lower[b] = b0;
    s.upper[b] = b1;
    surfaces_.push_back(s);
  };
  piece(lower[a], ol_a, lower[b], upper[b]);
  piece(ou_a, upper[a], lower[b], upper[b]);
  piece(ol_a, ou_a, lower[b], ol_b);
  piece(ol_a, ou_a, ou_b, upper[b]);
}

void SyntheticWorld::add_room(const Eigen::Vector3d& lower, const Eigen::Vector3d& upper, const RoomTextures& textures,
                              const Eigen::Vector3d& texture_origin, double door_half_width_m, double door_top_y,
                              double door_center_x, bool door_low, bool door_high) {
  auto face = [&](int axis, bool high, const SurfaceTexture& texture, bool door) {
    Eigen::Vector3d l = lower, u = upper;
    l[axis] = u[axis] = high ? upper[axis] : lower[axis];
    if (door && door_half_width_m > 0.0) {
      Eigen::Vector3d ol = l, ou = u;
      ol.x() = door_center_x - door_half_width_m;
      ou.x() = door_center_x + door_half_width_m;
      ol.y() = door_top_y;
      ou.y() = upper.y();
      add_wall(axis, l, u, texture, texture_origin, &ol, &ou);
    } else {
      add_wall(axis, l, u, texture, texture_origin);
    }
  };
  face(0, false, textures.x_low, false);
  face(0, true, textures.x_high, false);
  face(1, false, textures.y_low, false);
  face(1, true, textures.y_high, false);
  face(2, false, textures.z_low, door_low);
  face(2, true, textures.z_high, door_high);
}

void SyntheticWorld::add_corridor_z(const Eigen::Vector3d& lower, const Eigen::Vector3d& upper, std::uint64_t seed) {
  for (int axis = 0; axis < 2; ++axis) {
    for (int side = 0; side < 2; ++side) {
      Eigen::Vector3d l = lower, u = upper;
      l[axis] = u[axis] = side == 0 ? lower[axis] : upper[axis];
      SurfaceTexture texture;
      texture.seed = mix(seed * 4 + static_cast<std::uint64_t>(axis * 2 + side));
      add_wall(axis, l, u, texture, lower);
    }
  }
}

cv::Mat SyntheticWorld::render(const core::SE3& T_world_camera, const StereoCamera& camera) const {
  const std::vector<Plane> planes = planes_in_view(surfaces_, T_world_camera, camera);
  cv::Mat image(camera.height, camera.width, CV_8UC1, cv::Scalar(0));
  const Eigen::Matrix3d R = T_world_camera.rotation_matrix();
  const Eigen::Vector3d o = T_world_camera.translation();
  // Ray of pixel (u, v): R (x, y, 1) = x R.col(0) + y R.col(1) + R.col(2); the 2 x 2 sub-pixel
  // samples sit a quarter pixel off the centre.
  const Eigen::Vector3d step_u = R.col(0) / camera.fx, step_v = R.col(1) / camera.fy;
  const std::array<Eigen::Vector3d, 4> offsets{-0.25 * step_u - 0.25 * step_v, 0.25 * step_u - 0.25 * step_v,
                                               -0.25 * step_u + 0.25 * step_v, 0.25 * step_u + 0.25 * step_v};
  TextureCell cell;
  int previous = -1;
  for (int v = 0; v < camera.height; ++v) {
    unsigned char* row = image.ptr<unsigned char>(v);
    const Eigen::Vector3d row_start = R.col(2) - camera.cx * step_u + (static_cast<double>(v) - camera.cy) * step_v;
    for (int u = 0; u < camera.width; ++u) {
      const Eigen::Vector3d d = row_start + static_cast<double>(u) * step_u;
      double t = 0.0;
      const int hit = nearest_hit(planes, o, d, &t, previous);
      previous = hit;
      if (hit < 0) continue;
      const Plane& p = planes[static_cast<std::size_t>(hit)];
      double sum = 0.0;
      if (!p.textured) {
        sum = 4.0 * p.grey;
      } else {
        // A sub-pixel ray nearly parallel to the plane takes the texture where the centre ray hits.
        for (const Eigen::Vector3d& offset : offsets) {
          const double value = shade(p, o, d + offset, -1.0, cell);
          sum += value >= 0.0 ? value : shade(p, o, d, 128.0, cell);
        }
      }
      row[u] = static_cast<unsigned char>(std::clamp(std::lround(sum / 4.0), 0L, 255L));
    }
  }
  return image;
}

std::pair<cv::Mat, cv::Mat> SyntheticWorld::render_stereo(const core::SE3& T_world_left, const StereoCamera& camera) const {
  // The right image on a second thread: the two renderings share nothing but const data.
  const core::SE3 T_left_right(core::SO3(), Eigen::Vector3d(camera.baseline_m, 0.0, 0.0));
  std::future<cv::Mat> right = std::async(std::launch::async, [&] { return render(T_world_left * T_left_right, camera); });
  cv::Mat left = render(T_world_left, camera);
  return {left, right.get()};
}

cv::Mat SyntheticWorld::render_depth(const core::SE3& T_world_camera, const StereoCamera& camera) const {
  const std::vector<Plane> planes = planes_in_view(surfaces_, T_world_camera, camera);
  cv::Mat depth(camera.height, camera.width, CV_16UC1, cv::Scalar(0));
  for_each_pixel(T_world_camera, camera, [&](int u, int v, const Eigen::Vector3d& o, const Eigen::Matrix3d& R) {
    double t = 0.0;
    if (nearest_hit(planes, o, ray(R, camera, static_cast<double>(u), static_cast<double>(v)), &t) < 0) return;
    const double units = std::round(t * camera.depth_units_per_m);  // t is the camera z: the ray's z is 1
    if (units > 0.0 && units <= 65535.0) depth.at<std::uint16_t>(v, u) = static_cast<std::uint16_t>(units);
  });
  return depth;
}

double SyntheticWorld::textured_fraction(const core::SE3& T_world_camera, const StereoCamera& camera) const {
  const std::vector<Plane> planes = planes_in_view(surfaces_, T_world_camera, camera);
  std::size_t textured = 0;
  for_each_pixel(T_world_camera, camera, [&](int u, int v, const Eigen::Vector3d& o, const Eigen::Matrix3d& R) {
    double t = 0.0;
    const int hit = nearest_hit(planes, o, ray(R, camera, static_cast<double>(u), static_cast<double>(v)), &t);
    if (hit >= 0 && planes[static_cast<std::size_t>(hit)].textured) ++textured;
  });
  return static_cast<double>(textured) / (static_cast<double>(camera.width) * static_cast<double>(camera.height));
}

core::SE3 camera_pose(const Eigen::Vector3d& position, double yaw_rad, double pitch_rad) {
  // Yaw about the world y axis (down): Ry(yaw) z = (sin yaw, 0, cos yaw). Pitch about the camera
  // x axis: Rx(pitch) z = (0, -sin pitch, cos pitch), up for a positive pitch since y points down.
  const Eigen::Matrix3d yaw = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Matrix3d pitch = Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitX()).toRotationMatrix();
  return core::SE3(core::SO3::from_matrix(yaw * pitch), position);
}

std::vector<core::SE3> walk(const Eigen::Vector3d& from, const Eigen::Vector3d& to, double step_m, double yaw_rad,
                            double yaw_amplitude_rad, double lateral_amplitude_m, double period_m) {
  const double length = (to - from).norm();
  const int steps = std::max(1, static_cast<int>(std::lround(length / step_m)));
  std::vector<core::SE3> poses;
  for (int k = 0; k <= steps; ++k) {
    const double f = static_cast<double>(k) / static_cast<double>(steps);
    const double s = f * length;
    Eigen::Vector3d p = from + f * (to - from);
    p.x() += lateral_amplitude_m * std::sin(2.0 * kPi * s / (1.7 * period_m));
    poses.push_back(camera_pose(p, yaw_rad + yaw_amplitude_rad * std::sin(2.0 * kPi * s / period_m)));
  }
  return poses;
}

std::vector<core::SE3> turn(const Eigen::Vector3d& position, double yaw_from_rad, double yaw_to_rad, double step_rad) {
  const int steps = std::max(1, static_cast<int>(std::lround(std::abs(yaw_to_rad - yaw_from_rad) / step_rad)));
  std::vector<core::SE3> poses;
  for (int k = 0; k <= steps; ++k) {
    const double f = static_cast<double>(k) / static_cast<double>(steps);
    poses.push_back(camera_pose(position, yaw_from_rad + f * (yaw_to_rad - yaw_from_rad)));
  }
  return poses;
}

std::vector<core::SE3> hold(const core::SE3& pose, int count) {
  return std::vector<core::SE3>(static_cast<std::size_t>(std::max(0, count)), pose);
}

void append(std::vector<core::SE3>& a, const std::vector<core::SE3>& b) {
  std::size_t first = 0;
  if (!a.empty() && !b.empty() && (a.back().translation() - b.front().translation()).norm() < 1e-12 &&
      (a.back().rotation_matrix() - b.front().rotation_matrix()).norm() < 1e-12) {
    first = 1;
  }
  a.insert(a.end(), b.begin() + static_cast<std::ptrdiff_t>(first), b.end());
}

}  // namespace cairn::test
