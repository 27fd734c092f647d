#pragma once
// Test fixtures of the VO: small camera models (until vo's real models are used here) and a
// ray-cast renderer of a box room with procedurally textured walls, so VO tests can run on
// images with exact ground truth, for any lens (pinhole, 186-degree fisheye). Header-only,
// used by tests/vo/*_test.cc and tests/bench/vo_bench.cc.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "rigcal/camera/camera_model.h"

namespace rigcal::vo::testing {

// Ideal pinhole: u = fx x/z + cx.
class TestPinhole : public camera::CameraModel {
 public:
  TestPinhole(int width, int height, double fx, double fy, double cx, double cy)
      : camera::CameraModel(width, height), fx_(fx), fy_(fy), cx_(cx), cy_(cy) {}
  // A pinhole with the given horizontal field of view, principal point at the centre.
  static std::shared_ptr<TestPinhole> WithFov(int width, int height, double hfov_deg) {
    const double f = 0.5 * width / std::tan(0.5 * hfov_deg * M_PI / 180.0);
    return std::make_shared<TestPinhole>(width, height, f, f, 0.5 * (width - 1),
                                         0.5 * (height - 1));
  }
  std::string type() const override { return "pinhole"; }
  std::optional<Eigen::Vector2d> Project(const Eigen::Vector3d& p,
                                         Eigen::Matrix<double, 2, 3>* jacobian) const override {
    if (p.z() <= 1e-9) return std::nullopt;
    if (jacobian) {
      *jacobian << fx_ / p.z(), 0, -fx_ * p.x() / (p.z() * p.z()), 0, fy_ / p.z(),
          -fy_ * p.y() / (p.z() * p.z());
    }
    return Eigen::Vector2d(fx_ * p.x() / p.z() + cx_, fy_ * p.y() / p.z() + cy_);
  }
  std::optional<Eigen::Vector3d> Unproject(const Eigen::Vector2d& px,
                                           Eigen::Matrix<double, 3, 2>* jacobian) const override {
    const Eigen::Vector3d v((px.x() - cx_) / fx_, (px.y() - cy_) / fy_, 1.0);
    if (jacobian) {
      const double n = v.norm();
      const Eigen::Matrix3d dn = (Eigen::Matrix3d::Identity() - v * v.transpose() / (n * n)) / n;
      Eigen::Matrix<double, 3, 2> dv;
      dv << 1.0 / fx_, 0, 0, 1.0 / fy_, 0, 0;
      *jacobian = dn * dv;
    }
    return v.normalized();
  }
  double MaxFieldAngleDeg() const override {
    const double x = std::max(cx_, width() - cx_) / fx_;
    const double y = std::max(cy_, height() - cy_) / fy_;
    return std::atan(std::hypot(x, y)) * 180.0 / M_PI;
  }
  double PixelAngle() const override { return 1.0 / fx_; }
  std::unique_ptr<camera::CameraModel> Clone() const override {
    return std::make_unique<TestPinhole>(*this);
  }

 private:
  double fx_, fy_, cx_, cy_;
};

// Ideal equidistant fisheye: r = f theta, up to `max_angle_deg` from the axis (93 degrees =
// a 186-degree lens, where bearings have z < 0).
class TestEquidistant : public camera::CameraModel {
 public:
  TestEquidistant(int width, int height, double f, double cx, double cy, double max_angle_deg)
      : camera::CameraModel(width, height),
        f_(f),
        cx_(cx),
        cy_(cy),
        max_angle_(max_angle_deg * M_PI / 180) {}
  // The image circle of a `fov_deg` lens fills the smaller image side.
  static std::shared_ptr<TestEquidistant> WithFov(int width, int height, double fov_deg) {
    const double half = 0.5 * fov_deg * M_PI / 180.0;
    const double f = 0.5 * std::min(width, height) / half;
    return std::make_shared<TestEquidistant>(width, height, f, 0.5 * (width - 1),
                                             0.5 * (height - 1), 0.5 * fov_deg);
  }
  std::string type() const override { return "fisheye"; }
  std::optional<Eigen::Vector2d> Project(const Eigen::Vector3d& p,
                                         Eigen::Matrix<double, 2, 3>* jacobian) const override {
    const double n = p.norm();
    if (!(n > 0)) return std::nullopt;
    const double theta = std::acos(std::clamp(p.z() / n, -1.0, 1.0));
    if (theta > max_angle_) return std::nullopt;
    const double rho = std::hypot(p.x(), p.y());
    const double r = f_ * theta;
    Eigen::Vector2d px(cx_, cy_);
    if (rho > 1e-12) px += r * Eigen::Vector2d(p.x() / rho, p.y() / rho);
    if (jacobian) {  // numeric (tests only)
      for (int k = 0; k < 3; ++k) {
        Eigen::Vector3d d = Eigen::Vector3d::Zero();
        d(k) = 1e-7 * n;
        const auto a = Project(p + d, nullptr);
        const auto b = Project(p - d, nullptr);
        jacobian->col(k) =
            (a && b) ? Eigen::Vector2d((*a - *b) / (2e-7 * n)) : Eigen::Vector2d::Zero();
      }
    }
    return px;
  }
  std::optional<Eigen::Vector3d> Unproject(const Eigen::Vector2d& px,
                                           Eigen::Matrix<double, 3, 2>* jacobian) const override {
    const Eigen::Vector2d d(px.x() - cx_, px.y() - cy_);
    const double r = d.norm();
    const double theta = r / f_;
    if (theta > max_angle_) return std::nullopt;
    Eigen::Vector3d v(0, 0, 1);
    if (r > 1e-12)
      v = Eigen::Vector3d(std::sin(theta) * d.x() / r, std::sin(theta) * d.y() / r,
                          std::cos(theta));
    if (jacobian) jacobian->setZero();
    return v;
  }
  double MaxFieldAngleDeg() const override { return max_angle_ * 180.0 / M_PI; }
  double PixelAngle() const override { return 1.0 / f_; }
  std::unique_ptr<camera::CameraModel> Clone() const override {
    return std::make_unique<TestEquidistant>(*this);
  }

 private:
  double f_, cx_, cy_, max_angle_;
};

// A box room [-h, h]^3 (h = half_size per axis) whose six walls carry procedural grey
// textures: blobs, rectangles and discs of random grey levels over smooth noise.
class SyntheticRoom {
 public:
  explicit SyntheticRoom(const Eigen::Vector3d& half_size = Eigen::Vector3d(4, 3, 5),
                         uint32_t seed = 7, int texture_px = 1024)
      : half_(half_size) {
    std::mt19937 rng(seed);
    for (auto& t : textures_) t = MakeTexture(texture_px, &rng);
  }

  // Unit bearings of every pixel of `camera` (row-major; invalid pixels have a zero vector).
  static std::vector<Eigen::Vector3f> Rays(const camera::CameraModel& camera) {
    std::vector<Eigen::Vector3f> rays(static_cast<size_t>(camera.width()) * camera.height(),
                                      Eigen::Vector3f::Zero());
    for (int y = 0; y < camera.height(); ++y) {
      for (int x = 0; x < camera.width(); ++x) {
        const auto f = camera.Unproject(Eigen::Vector2d(x, y), nullptr);
        if (f) rays[static_cast<size_t>(y) * camera.width() + x] = f->normalized().cast<float>();
      }
    }
    return rays;
  }

  // Grey image seen by a camera at (R world_from_cam, C) inside the room, with Gaussian noise
  // of `noise_sigma` grey levels (seeded by `noise_seed`). Pixels outside the lens are black.
  cv::Mat Render(const camera::CameraModel& camera, const std::vector<Eigen::Vector3f>& rays,
                 const Eigen::Matrix3d& R_world_from_cam, const Eigen::Vector3d& C,
                 double noise_sigma = 1.0, uint32_t noise_seed = 1) const {
    cv::Mat image(camera.height(), camera.width(), CV_32FC1);
    const Eigen::Matrix3f r = R_world_from_cam.cast<float>();
    const Eigen::Vector3f c = C.cast<float>();
    const Eigen::Vector3f h = half_.cast<float>();
    for (int y = 0; y < image.rows; ++y) {
      float* row = image.ptr<float>(y);
      for (int x = 0; x < image.cols; ++x) {
        const Eigen::Vector3f& f = rays[static_cast<size_t>(y) * image.cols + x];
        if (f.squaredNorm() == 0.f) {
          row[x] = 0.f;
          continue;
        }
        const Eigen::Vector3f d = r * f;
        float best = 1e30f;
        int wall = 0;
        for (int a = 0; a < 3; ++a) {
          if (std::abs(d[a]) < 1e-9f) continue;
          const float bound = d[a] > 0 ? h[a] : -h[a];
          const float t = (bound - c[a]) / d[a];
          if (t > 0 && t < best) {
            best = t;
            wall = 2 * a + (d[a] > 0 ? 1 : 0);
          }
        }
        const Eigen::Vector3f p = c + best * d;
        const int a = wall / 2;
        const int u_axis = (a + 1) % 3;
        const int v_axis = (a + 2) % 3;
        const float u = (p[u_axis] + h[u_axis]) / (2 * h[u_axis]);
        const float v = (p[v_axis] + h[v_axis]) / (2 * h[v_axis]);
        row[x] = Sample(textures_[wall], u, v);
      }
    }
    if (noise_sigma > 0) {
      cv::Mat noise(image.size(), CV_32FC1);
      cv::theRNG().state = noise_seed;
      cv::randn(noise, 0.0, noise_sigma);
      image += noise;
    }
    cv::Mat out;
    image.convertTo(out, CV_8UC1);
    return out;
  }

  const Eigen::Vector3d& half_size() const { return half_; }

 private:
  static cv::Mat MakeTexture(int size, std::mt19937* rng) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    cv::Mat small(16, 16, CV_32FC1);
    for (int y = 0; y < small.rows; ++y) {
      for (int x = 0; x < small.cols; ++x) small.at<float>(y, x) = 60.f + 120.f * u(*rng);
    }
    cv::Mat tex;
    cv::resize(small, tex, cv::Size(size, size), 0, 0, cv::INTER_CUBIC);
    const int shapes = size * size / 900;
    for (int i = 0; i < shapes; ++i) {
      const cv::Point centre(static_cast<int>(u(*rng) * size), static_cast<int>(u(*rng) * size));
      const int extent = 4 + static_cast<int>(u(*rng) * size / 48.0);
      const double grey = 20.0 + 215.0 * u(*rng);
      if (u(*rng) < 0.5) {
        cv::rectangle(tex, centre,
                      centre + cv::Point(extent, static_cast<int>(extent * (0.5 + u(*rng)))),
                      cv::Scalar(grey), cv::FILLED, cv::LINE_AA);
      } else {
        cv::circle(tex, centre, extent / 2 + 2, cv::Scalar(grey), cv::FILLED, cv::LINE_AA);
      }
    }
    cv::GaussianBlur(tex, tex, cv::Size(0, 0), 1.0);
    return tex;
  }

  static float Sample(const cv::Mat& tex, float u, float v) {
    const float x = std::clamp(u, 0.f, 1.f) * (tex.cols - 1);
    const float y = std::clamp(v, 0.f, 1.f) * (tex.rows - 1);
    const int x0 = std::min(static_cast<int>(x), tex.cols - 2);
    const int y0 = std::min(static_cast<int>(y), tex.rows - 2);
    const float ax = x - x0;
    const float ay = y - y0;
    const float* r0 = tex.ptr<float>(y0);
    const float* r1 = tex.ptr<float>(y0 + 1);
    return (1 - ay) * ((1 - ax) * r0[x0] + ax * r0[x0 + 1]) +
           ay * ((1 - ax) * r1[x0] + ax * r1[x0 + 1]);
  }

  Eigen::Vector3d half_;
  std::array<cv::Mat, 6> textures_;
};

// A smooth general motion inside the room: frame k at 20 Hz, translation a few cm and
// rotation about half a degree per frame. Returns (R world_from_cam, C).
inline std::pair<Eigen::Matrix3d, Eigen::Vector3d> RoomTrajectory(int k, double speed = 1.0) {
  const double t = 0.05 * k * speed;
  const Eigen::Vector3d C(1.2 * std::sin(0.5 * t), 0.4 * std::sin(0.7 * t + 0.3),
                          0.9 * std::sin(0.33 * t + 1.0) - 0.5);
  const double yaw = 0.35 * std::sin(0.4 * t);
  const double pitch = 0.15 * std::sin(0.6 * t + 0.5);
  const double roll = 0.1 * std::sin(0.5 * t + 1.3);
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitX()) *
                             Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()))
                                .toRotationMatrix();
  return {R, C};
}

}  // namespace rigcal::vo::testing
