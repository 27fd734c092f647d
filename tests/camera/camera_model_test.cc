// SPDX-License-Identifier: Apache-2.0
// Camera models: round trips over the image and over random bearings, Jacobians against central
// differences, field-of-view limits (beyond 90 degrees for fisheye and scaramuzza), the OCamCalib
// conventions of the scaramuzza model, and spec validation naming the field.
// Over 600 lines: every model through the same round-trip and Jacobian checks, side by side.
#include "rigcal/camera/camera_model.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <ostream>
#include <random>
#include <string>
#include <vector>

#include "rigcal/camera/camera_spec.h"

namespace rigcal::camera {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// EuRoC MAV cam0 (shared/data/euroc_v101_static/mav0/cam0/sensor.yaml): real radtan values.
CameraSpec EurocPinhole() {
  CameraSpec spec;
  spec.name = "euroc_cam0";
  spec.model = CameraSpec::Model::kPinhole;
  spec.width = 752;
  spec.height = 480;
  spec.intrinsics = {458.654, 457.296, 367.215, 248.375};
  spec.distortion = {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05};
  return spec;
}

// A wide pinhole with k3 and strong tangential terms.
CameraSpec WidePinholeK3() {
  CameraSpec spec;
  spec.name = "wide";
  spec.model = CameraSpec::Model::kPinhole;
  spec.width = 640;
  spec.height = 480;
  spec.intrinsics = {300.0, 302.0, 318.0, 243.0};
  spec.distortion = {-0.25, 0.06, 2e-3, -1.5e-3, -0.004};
  return spec;
}

// A Kalibr-like equidistant fisheye with a 186-degree circular image.
CameraSpec Fisheye186() {
  CameraSpec spec;
  spec.name = "fisheye";
  spec.model = CameraSpec::Model::kFisheye;
  spec.width = 800;
  spec.height = 800;
  spec.intrinsics = {240.0, 239.0, 401.0, 398.0};
  spec.distortion = {0.02, -0.005, 0.001, -0.0001};
  spec.max_field_angle_deg = 93.0;
  return spec;
}

// A fisheye on a small sensor: automatic field angle (the corners).
CameraSpec FisheyeAutomatic() {
  CameraSpec spec = Fisheye186();
  spec.name = "fisheye_auto";
  spec.width = 640;
  spec.height = 480;
  spec.intrinsics = {190.0, 190.5, 322.0, 236.0};
  spec.max_field_angle_deg = 0.0;
  return spec;
}

// An OCamCalib-like omnidirectional camera with an affine part.
CameraSpec OcamLike() {
  CameraSpec spec;
  spec.name = "ocam";
  spec.model = CameraSpec::Model::kScaramuzza;
  spec.width = 900;
  spec.height = 900;
  spec.poly = {-230.0, 0.0, 1.2e-3, -1.5e-6, 4e-9};
  spec.center = {451.3, 448.7};
  spec.affine = {1.0005, 3e-4, -2e-4};
  spec.max_field_angle_deg = 93.0;
  return spec;
}

CameraSpec EquidistantScaramuzza() {
  auto spec = ScaramuzzaSpecForEquidistant("omni", 800, 800, 240.0, 399.5, 400.5, 93.0);
  EXPECT_TRUE(spec) << spec.error();
  return *spec;
}

std::unique_ptr<CameraModel> Make(const CameraSpec& spec) {
  auto model = MakeCameraModel(spec);
  EXPECT_TRUE(model) << spec.name << ": " << model.error();
  return model ? std::move(*model) : nullptr;
}

double AngleBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

double FieldAngle(const Eigen::Vector3d& p) { return std::atan2(p.head<2>().norm(), p.z()); }

// Uniform random bearing with field angle in [0, max_angle].
Eigen::Vector3d RandomBearing(std::mt19937& rng, double max_angle) {
  std::uniform_real_distribution<double> cos_theta(std::cos(max_angle), 1.0);
  std::uniform_real_distribution<double> azimuth(-std::numbers::pi, std::numbers::pi);
  const double c = cos_theta(rng);
  const double s = std::sqrt(std::max(0.0, 1.0 - c * c));
  const double a = azimuth(rng);
  return Eigen::Vector3d(s * std::cos(a), s * std::sin(a), c);
}

struct Case {
  std::string label;
  CameraSpec (*spec)();
  bool whole_image_valid;  // every pixel of the image is inside the field of view
};

// Readable test names and failure messages.
void PrintTo(const Case& c, std::ostream* out) { *out << c.label; }

class CameraModelTest : public ::testing::TestWithParam<Case> {};

TEST_P(CameraModelTest, RoundTripOverTheWholeImage) {
  const CameraSpec spec = GetParam().spec();
  auto model = Make(spec);
  ASSERT_TRUE(model);
  EXPECT_EQ(model->type(), std::string(ModelName(spec.model)));
  double worst_px = 0.0;
  int valid = 0;
  int total = 0;
  for (int v = 0; v < spec.height; ++v) {
    for (int u = 0; u < spec.width; ++u) {
      // Pixel centres plus an offset so that no sample sits exactly on the principal point.
      const Eigen::Vector2d pixel(u + 0.37 * ((u + v) % 3) / 2.0, v + 0.21 * (u % 2));
      ++total;
      const auto bearing = model->Unproject(pixel);
      if (!bearing) {
        EXPECT_FALSE(GetParam().whole_image_valid) << "pixel " << pixel.transpose();
        continue;
      }
      ++valid;
      ASSERT_NEAR(bearing->norm(), 1.0, 1e-14);
      EXPECT_LE(FieldAngle(*bearing), model->MaxFieldAngleDeg() * kDeg * (1 + 1e-12));
      // Any distance along the bearing projects to the same pixel.
      const auto back = model->Project(*bearing * 3.7);
      ASSERT_TRUE(back) << "pixel " << pixel.transpose();
      worst_px = std::max(worst_px, (*back - pixel).norm());
    }
  }
  EXPECT_LE(worst_px, 1e-9) << GetParam().label;
  if (!GetParam().whole_image_valid) {
    // A circular image: the inscribed disc is valid, the corners are not.
    EXPECT_GT(valid, total / 2);
    EXPECT_LT(valid, total);
  }
}

TEST_P(CameraModelTest, RoundTripOverRandomBearingsInsideTheFieldOfView) {
  auto model = Make(GetParam().spec());
  ASSERT_TRUE(model);
  const double max_angle = model->MaxFieldAngleDeg() * kDeg;
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> distance(0.05, 200.0);
  double worst_rad = 0.0;
  double worst_px = 0.0;
  for (int i = 0; i < 20000; ++i) {
    const Eigen::Vector3d bearing = RandomBearing(rng, max_angle * 0.9999);
    const auto pixel = model->Project(bearing * distance(rng));
    ASSERT_TRUE(pixel) << "bearing " << bearing.transpose();
    const auto back = model->Unproject(*pixel);
    ASSERT_TRUE(back) << "pixel " << pixel->transpose();
    worst_rad = std::max(worst_rad, AngleBetween(*back, bearing));
    worst_px = std::max(worst_px, (*model->Project(*back) - *pixel).norm());
  }
  // 1e-9 px expressed as an angle through the pixel size at the centre (the pixel angle grows
  // at most a few times towards the edge of these lenses).
  EXPECT_LE(worst_rad, 1e-9 * model->PixelAngle());
  EXPECT_LE(worst_px, 1e-9);
}

TEST_P(CameraModelTest, ProjectionJacobianMatchesCentralDifferences) {
  auto model = Make(GetParam().spec());
  ASSERT_TRUE(model);
  const double max_angle = model->MaxFieldAngleDeg() * kDeg;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> distance(0.2, 50.0);
  std::vector<Eigen::Vector3d> points;
  // Each draw in its own statement: the order of a call's (or an operator's) operands is
  // unspecified, and this order keeps the samples the test had with GCC.
  for (int i = 0; i < 2000; ++i) {
    const double d = distance(rng);
    points.push_back(RandomBearing(rng, max_angle * 0.999) * d);
  }
  points.push_back(Eigen::Vector3d(0.0, 0.0, 2.0));     // on the axis
  points.push_back(Eigen::Vector3d(1e-9, -2e-9, 1.5));  // next to it
  for (const Eigen::Vector3d& point : points) {
    Eigen::Matrix<double, 2, 3> analytic;
    const auto pixel = model->Project(point, &analytic);
    ASSERT_TRUE(pixel);
    const double h = 1e-6 * point.norm();
    Eigen::Matrix<double, 2, 3> numeric;
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector3d delta = Eigen::Vector3d::Zero();
      delta[k] = h;
      const auto plus = model->Project(point + delta);
      const auto minus = model->Project(point - delta);
      ASSERT_TRUE(plus && minus);
      numeric.col(k) = (*plus - *minus) / (2 * h);
    }
    EXPECT_LE((analytic - numeric).norm(), 1e-6 * analytic.norm())
        << "point " << point.transpose() << "\nanalytic\n"
        << analytic << "\nnumeric\n"
        << numeric;
  }
}

TEST_P(CameraModelTest, UnprojectionJacobianMatchesCentralDifferences) {
  const CameraSpec spec = GetParam().spec();
  auto model = Make(spec);
  ASSERT_TRUE(model);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, spec.width - 1.0);
  std::uniform_real_distribution<double> v(0.0, spec.height - 1.0);
  std::vector<Eigen::Vector2d> pixels;
  for (int i = 0; i < 4000; ++i) {
    const double y = v(rng);  // y first: the samples the test had with GCC (see above)
    pixels.emplace_back(u(rng), y);
  }
  // The principal point / centre and a pixel next to it.
  pixels.push_back(*model->Project(Eigen::Vector3d(0.0, 0.0, 1.0)));
  pixels.push_back(pixels.back() + Eigen::Vector2d(1e-7, -3e-7));
  int checked = 0;
  for (const Eigen::Vector2d& pixel : pixels) {
    Eigen::Matrix<double, 3, 2> analytic;
    if (!model->Unproject(pixel, &analytic)) continue;  // outside a circular image
    const double h = 1e-3;
    Eigen::Matrix<double, 3, 2> numeric;
    bool inside = true;
    for (int k = 0; k < 2; ++k) {
      Eigen::Vector2d delta = Eigen::Vector2d::Zero();
      delta[k] = h;
      const auto plus = model->Unproject(pixel + delta);
      const auto minus = model->Unproject(pixel - delta);
      if (!plus || !minus) {
        inside = false;
        break;
      }
      numeric.col(k) = (*plus - *minus) / (2 * h);
    }
    if (!inside) continue;
    ++checked;
    EXPECT_LE((analytic - numeric).norm(), 1e-6 * analytic.norm())
        << "pixel " << pixel.transpose() << "\nanalytic\n"
        << analytic << "\nnumeric\n"
        << numeric;
  }
  EXPECT_GT(checked, 2000);
}

TEST_P(CameraModelTest, PointsOutsideTheFieldOfViewAreRejected) {
  const CameraSpec spec = GetParam().spec();
  auto model = Make(spec);
  ASSERT_TRUE(model);
  const double max_angle = model->MaxFieldAngleDeg() * kDeg;
  for (const double azimuth : {0.0, 0.7, 2.0, -2.5}) {
    const Eigen::Vector3d direction(std::cos(azimuth), std::sin(azimuth), 0.0);
    const auto at = [&](double theta) {
      return Eigen::Vector3d(std::sin(theta) * direction.x(), std::sin(theta) * direction.y(),
                             std::cos(theta));
    };
    EXPECT_TRUE(model->Project(at(max_angle * (1 - 1e-6))));
    EXPECT_FALSE(model->Project(at(max_angle * (1 + 1e-6)) * 5.0));
    EXPECT_FALSE(model->Project(at(max_angle + 10 * kDeg)));
    // The pixel of the boundary and one just beyond it (radially, away from the centre).
    const Eigen::Vector2d centre = *model->Project(Eigen::Vector3d(0, 0, 1));
    const Eigen::Vector2d edge = *model->Project(at(max_angle * (1 - 1e-9)));
    EXPECT_TRUE(model->Unproject(edge));
    EXPECT_FALSE(model->Unproject(edge + 0.01 * (edge - centre).normalized()));
  }
  EXPECT_FALSE(model->Project(Eigen::Vector3d(0, 0, -1)));  // straight behind
  EXPECT_FALSE(model->Project(Eigen::Vector3d(0, 0, 0)));   // the centre of projection
  EXPECT_FALSE(model->Unproject(Eigen::Vector2d(1e7, -1e7)));
  EXPECT_FALSE(model->Unproject(Eigen::Vector2d(std::nan(""), 3.0)));
  EXPECT_FALSE(model->Project(Eigen::Vector3d(std::nan(""), 0.0, 1.0)));
}

TEST_P(CameraModelTest, CloneBehavesLikeTheOriginal) {
  auto model = Make(GetParam().spec());
  ASSERT_TRUE(model);
  const std::unique_ptr<CameraModel> clone = model->Clone();
  EXPECT_EQ(clone->type(), model->type());
  EXPECT_EQ(clone->width(), model->width());
  EXPECT_EQ(clone->MaxFieldAngleDeg(), model->MaxFieldAngleDeg());
  const Eigen::Vector3d point(0.3, -0.2, 1.0);
  EXPECT_EQ(*clone->Project(point), *model->Project(point));
}

INSTANTIATE_TEST_SUITE_P(
    Models, CameraModelTest,
    ::testing::Values(Case{"euroc_pinhole", &EurocPinhole, true},
                      Case{"wide_pinhole_k3", &WidePinholeK3, true},
                      Case{"fisheye_186", &Fisheye186, false},
                      Case{"fisheye_automatic", &FisheyeAutomatic, true},
                      Case{"ocam_like", &OcamLike, false},
                      Case{"equidistant_scaramuzza", &EquidistantScaramuzza, false}),
    [](const ::testing::TestParamInfo<Case>& info) { return info.param.label; });

TEST(CameraModel, PinholeWithoutDistortionIsTheTextbookProjection) {
  CameraSpec spec = EurocPinhole();
  spec.distortion.clear();
  auto model = Make(spec);
  ASSERT_TRUE(model);
  const Eigen::Vector3d point(0.4, -0.3, 2.0);
  const Eigen::Vector2d pixel = *model->Project(point);
  EXPECT_NEAR(pixel.x(), 458.654 * 0.2 + 367.215, 1e-12);
  EXPECT_NEAR(pixel.y(), 457.296 * -0.15 + 248.375, 1e-12);
  EXPECT_NEAR(model->PixelAngle(), 1.0 / std::sqrt(458.654 * 457.296), 1e-15);
  EXPECT_FALSE(model->Project(Eigen::Vector3d(0.1, 0.1, 0.0)));
  EXPECT_FALSE(model->Project(Eigen::Vector3d(0.1, 0.1, -1.0)));
}

TEST(CameraModel, PinholeRadtanMatchesTheOpenCvFormula) {
  const CameraSpec spec = WidePinholeK3();
  auto model = Make(spec);
  ASSERT_TRUE(model);
  const Eigen::Vector3d point(-0.5, 0.35, 1.3);
  const double x = point.x() / point.z();
  const double y = point.y() / point.z();
  const double r2 = x * x + y * y;
  const auto& k = spec.distortion;  // k1 k2 p1 p2 k3
  const double radial = 1 + k[0] * r2 + k[1] * r2 * r2 + k[4] * r2 * r2 * r2;
  const double xd = x * radial + 2 * k[2] * x * y + k[3] * (r2 + 2 * x * x);
  const double yd = y * radial + k[2] * (r2 + 2 * y * y) + 2 * k[3] * x * y;
  const Eigen::Vector2d pixel = *model->Project(point);
  EXPECT_NEAR(pixel.x(), spec.intrinsics[0] * xd + spec.intrinsics[2], 1e-11);
  EXPECT_NEAR(pixel.y(), spec.intrinsics[1] * yd + spec.intrinsics[3], 1e-11);
}

TEST(CameraModel, AutomaticFieldAngleIsTheFarthestCorner) {
  for (const CameraSpec& spec : {EurocPinhole(), WidePinholeK3(), FisheyeAutomatic()}) {
    auto model = Make(spec);
    ASSERT_TRUE(model);
    double corner = 0.0;
    for (const double u : {-0.5, spec.width - 0.5}) {
      for (const double v : {-0.5, spec.height - 0.5}) {
        const auto bearing = model->Unproject(Eigen::Vector2d(u, v));
        ASSERT_TRUE(bearing) << spec.name;
        corner = std::max(corner, FieldAngle(*bearing));
      }
    }
    EXPECT_GE(model->MaxFieldAngleDeg() * kDeg, corner * (1 - 1e-12)) << spec.name;
    EXPECT_LE(model->MaxFieldAngleDeg() * kDeg, corner * 1.001) << spec.name;
  }
}

TEST(CameraModel, PinholeDomainStopsWhereTheDistortionFoldsBack) {
  // r_d = r (1 - 0.6 r^2) is largest at r = 1 / sqrt(1.8); beyond it the naive formula maps
  // points far outside the field of view back into the image.
  CameraSpec spec = EurocPinhole();
  spec.intrinsics = {200.0, 200.0, 376.0, 240.0};
  spec.distortion = {-0.6, 0.0, 0.0, 0.0};
  auto model = Make(spec);
  ASSERT_TRUE(model);
  const double r_fold = 1.0 / std::sqrt(1.8);
  EXPECT_LE(std::tan(model->MaxFieldAngleDeg() * kDeg), r_fold);
  EXPECT_GE(std::tan(model->MaxFieldAngleDeg() * kDeg), r_fold * 0.98);
  // At r = 1.2 the naive pixel radius is 200 * 1.2 * (1 - 0.864) = 33 px: inside the image.
  EXPECT_FALSE(model->Project(Eigen::Vector3d(1.2, 0.0, 1.0)));
  // Inside the domain the round trip holds.
  const Eigen::Vector3d inside(0.5, 0.3, 1.0);
  EXPECT_LE(AngleBetween(*model->Unproject(*model->Project(inside)), inside), 1e-14);
  // Asking for more than the fold is an error naming the field.
  spec.max_field_angle_deg = 45.0;
  const std::string error = spec.Check().message();
  EXPECT_FALSE(spec.Check().ok());
  EXPECT_EQ(error.rfind("max_field_angle_deg: ", 0), 0u) << error;
}

TEST(CameraModel, FisheyeSeesBehindTheCameraUpToItsFieldAngle) {
  auto model = Make(Fisheye186());
  ASSERT_TRUE(model);
  EXPECT_DOUBLE_EQ(model->MaxFieldAngleDeg(), 93.0);
  const double theta = 92.5 * kDeg;
  const Eigen::Vector3d behind(std::sin(theta) * 0.6, std::sin(theta) * 0.8, std::cos(theta));
  ASSERT_LT(behind.z(), 0.0);
  const auto pixel = model->Project(behind);
  ASSERT_TRUE(pixel);
  EXPECT_TRUE(model->InImage(*pixel));
  // Equidistant: the pixel radius is f theta_d(theta).
  const double t2 = theta * theta;
  const double theta_d =
      theta * (1 + 0.02 * t2 - 0.005 * t2 * t2 + 0.001 * t2 * t2 * t2 - 0.0001 * t2 * t2 * t2 * t2);
  EXPECT_NEAR(pixel->x(), 401.0 + 240.0 * theta_d * 0.6, 1e-10);
  EXPECT_NEAR(pixel->y(), 398.0 + 239.0 * theta_d * 0.8, 1e-10);
  EXPECT_LE(AngleBetween(*model->Unproject(*pixel), behind), 1e-14);
  EXPECT_FALSE(model->Project(Eigen::Vector3d(std::sin(94 * kDeg), 0, std::cos(94 * kDeg))));
}

// OCamCalib's cam2world (ocam_functions.c) in its own frame and pixel order, mapped to ours:
// pixel (row, column) = (v, u), centre (xc, yc) = (cy, cx), point (x_o, y_o, z_o) = (y, x, -z).
Eigen::Vector3d OcamCam2World(const CameraSpec& spec, const Eigen::Vector2d& pixel) {
  const double xc = spec.center[1];
  const double yc = spec.center[0];
  const double c = spec.affine[0];
  const double d = spec.affine[1];
  const double e = spec.affine[2];
  const double row = pixel.y();
  const double col = pixel.x();
  const double invdet = 1.0 / (c - d * e);
  const double xp = invdet * ((row - xc) - d * (col - yc));
  const double yp = invdet * (-e * (row - xc) + c * (col - yc));
  const double r = std::sqrt(xp * xp + yp * yp);
  double zp = 0.0;
  for (size_t i = 0; i < spec.poly.size(); ++i) zp += spec.poly[i] * std::pow(r, i);
  const Eigen::Vector3d ocam = Eigen::Vector3d(xp, yp, zp).normalized();
  return Eigen::Vector3d(ocam.y(), ocam.x(), -ocam.z());
}

TEST(CameraModel, ScaramuzzaFollowsOcamCalibConventions) {
  const CameraSpec spec = OcamLike();
  auto model = Make(spec);
  ASSERT_TRUE(model);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> coordinate(0.0, 899.0);
  int checked = 0;
  for (int i = 0; i < 2000; ++i) {
    const double y = coordinate(rng);  // y first: the samples the test had with GCC (see above)
    const Eigen::Vector2d pixel(coordinate(rng), y);
    const auto bearing = model->Unproject(pixel);
    if (!bearing) continue;
    ++checked;
    EXPECT_LE(AngleBetween(*bearing, OcamCam2World(spec, pixel)), 1e-14);
  }
  EXPECT_GT(checked, 1000);
  // The centre looks along +z; a pixel to the right of it looks right (+x), one below looks
  // down (+y).
  const Eigen::Vector2d centre(spec.center[0], spec.center[1]);
  EXPECT_LE(AngleBetween(*model->Unproject(centre), Eigen::Vector3d::UnitZ()), 1e-15);
  EXPECT_GT(model->Unproject(centre + Eigen::Vector2d(50, 0))->x(), 0.0);
  EXPECT_GT(model->Unproject(centre + Eigen::Vector2d(0, 50))->y(), 0.0);
  // The field angle at radius rho (no affine part) is atan2(rho, -F(rho)): 93 deg near 440 px.
  EXPECT_NEAR(model->MaxFieldAngleDeg(), 93.0, 1e-9);
}

TEST(CameraModel, ScaramuzzaUsesAGivenInversePolyOnlyAsAStartingPoint) {
  CameraSpec spec = EquidistantScaramuzza();
  // The ideal equidistant lens has rho = f theta = f (phi + pi / 2) exactly; 0.3 px off.
  spec.inverse_poly = {240.0 * std::numbers::pi / 2 + 0.3, 240.0};
  auto model = Make(spec);
  ASSERT_TRUE(model);
  std::mt19937 rng(5);
  for (int i = 0; i < 1000; ++i) {
    const Eigen::Vector3d bearing = RandomBearing(rng, 92.9 * kDeg);
    const Eigen::Vector2d pixel = *model->Project(bearing);
    EXPECT_LE(AngleBetween(*model->Unproject(pixel), bearing), 1e-9 * model->PixelAngle());
  }
  // In degrees instead of radians: rejected, naming the field.
  spec.inverse_poly = {240.0 * 90.0, 240.0 * 180.0 / std::numbers::pi};
  const std::string error = spec.Check().message();
  EXPECT_FALSE(spec.Check().ok());
  EXPECT_EQ(error.rfind("inverse_poly: ", 0), 0u) << error;
}

TEST(CameraModel, EquidistantScaramuzzaSpecApproximatesTheIdealLens) {
  const CameraSpec spec = EquidistantScaramuzza();
  EXPECT_EQ(spec.model, CameraSpec::Model::kScaramuzza);
  ASSERT_GE(spec.poly.size(), 3u);
  EXPECT_EQ(spec.poly[0], -240.0);
  EXPECT_EQ(spec.poly[1], 0.0);
  auto model = Make(spec);
  ASSERT_TRUE(model);
  EXPECT_NEAR(model->MaxFieldAngleDeg(), 93.0, 1e-9);
  const Eigen::Vector2d centre(399.5, 400.5);
  for (double theta_deg = 0.0; theta_deg <= 93.0; theta_deg += 0.5) {
    const double theta = theta_deg * kDeg;
    for (const double azimuth : {0.3, 1.9, -2.2}) {
      const Eigen::Vector3d bearing(std::sin(theta) * std::cos(azimuth),
                                    std::sin(theta) * std::sin(azimuth), std::cos(theta));
      const auto pixel = model->Project(bearing);
      ASSERT_TRUE(pixel) << theta_deg;
      // Radius f theta, along the azimuth.
      EXPECT_NEAR((*pixel - centre).norm(), 240.0 * theta, 1e-3) << theta_deg;
      if (theta_deg > 0) {
        EXPECT_NEAR(std::atan2(pixel->y() - centre.y(), pixel->x() - centre.x()), azimuth, 1e-12);
      }
    }
  }
  // Both 186-degree halves of a back-to-back pair: 92 degrees is inside the image circle.
  const auto behind = model->Project(Eigen::Vector3d(std::sin(92 * kDeg), 0, std::cos(92 * kDeg)));
  ASSERT_TRUE(behind);
  EXPECT_TRUE(model->InImage(*behind));
  // Bad arguments.
  EXPECT_FALSE(ScaramuzzaSpecForEquidistant("x", 800, 800, -1.0, 400, 400, 93));
  EXPECT_FALSE(ScaramuzzaSpecForEquidistant("x", 800, 800, 240, 900, 400, 93));
  EXPECT_FALSE(ScaramuzzaSpecForEquidistant("x", 800, 800, 240, 400, 400, 150));
  // Wider lenses fit too.
  for (const double max_deg : {30.0, 60.0, 120.0, 140.0}) {
    auto wide = ScaramuzzaSpecForEquidistant("w", 1000, 1000, 150.0, 500, 500, max_deg);
    ASSERT_TRUE(wide) << max_deg << ": " << wide.error();
    auto wide_model = Make(*wide);
    ASSERT_TRUE(wide_model);
    const double theta = max_deg * kDeg * 0.99;
    const auto pixel = wide_model->Project(Eigen::Vector3d(std::sin(theta), 0, std::cos(theta)));
    ASSERT_TRUE(pixel);
    EXPECT_NEAR(pixel->x() - 500, 150.0 * theta, 1e-3) << max_deg;
  }
}

struct InvalidCase {
  std::string label;
  CameraSpec spec;
  std::string field;
};

std::vector<InvalidCase> InvalidCases() {
  std::vector<InvalidCase> cases;
  const auto add = [&](std::string label, CameraSpec spec, std::string field) {
    cases.push_back({std::move(label), std::move(spec), std::move(field)});
  };
  CameraSpec s = EurocPinhole();
  s.width = 0;
  add("zero width", s, "resolution");
  s = EurocPinhole();
  s.intrinsics[1] = -457.0;
  add("negative fy", s, "intrinsics");
  s = EurocPinhole();
  s.intrinsics[0] = std::nan("");
  add("nan fx", s, "intrinsics");
  s = EurocPinhole();
  s.intrinsics[2] = 900.0;
  add("principal point outside", s, "intrinsics");
  s = EurocPinhole();
  s.distortion = {0.1, 0.2, 0.3};
  add("three radtan coefficients", s, "distortion");
  s = EurocPinhole();
  s.distortion[1] = std::numeric_limits<double>::infinity();
  add("infinite k2", s, "distortion");
  s = EurocPinhole();
  s.max_field_angle_deg = 90.0;
  add("pinhole 90 deg", s, "max_field_angle_deg");
  s = EurocPinhole();
  s.poly = {-200.0};
  add("pinhole with poly", s, "poly");
  s = Fisheye186();
  s.distortion = {0.1, 0.2, 0.3, 0.4, 0.5};
  add("five fisheye coefficients", s, "distortion");
  s = Fisheye186();
  s.max_field_angle_deg = 180.0;
  add("fisheye 180 deg", s, "max_field_angle_deg");
  s = Fisheye186();
  s.distortion = {-0.5, 0.0, 0.0, 0.0};  // theta_d' = 1 - 1.5 theta^2: folds at 46.8 deg
  add("fisheye folding before its field angle", s, "max_field_angle_deg");
  s = OcamLike();
  s.poly = {230.0, 0.0, -1.2e-3};
  add("positive a0", s, "poly");
  s = OcamLike();
  s.poly.clear();
  add("no poly", s, "poly");
  s = OcamLike();
  s.affine = {0.0, 1.0, 1.0};
  add("singular affine", s, "affine");
  s = OcamLike();
  s.center = {-10.0, 400.0};
  add("centre outside", s, "center");
  s = OcamLike();
  s.intrinsics = {230, 230, 450, 450};
  add("scaramuzza with intrinsics", s, "intrinsics");
  s = OcamLike();
  s.poly = {-230.0, 0.0, 1.2e-3, -1.5e-6};  // the field angle peaks near 79 deg, then decreases
  add("scaramuzza beyond its polynomial", s, "max_field_angle_deg");
  return cases;
}

TEST(CameraSpec, InvalidSpecsAreRejectedNamingTheField) {
  for (const InvalidCase& c : InvalidCases()) {
    const Status status = c.spec.Check();
    EXPECT_FALSE(status.ok()) << c.label;
    const std::string& error = status.message();
    EXPECT_EQ(error.rfind(c.field + ": ", 0), 0u) << c.label << ": " << error;
    // "<field>: <what>" with a non-empty <what>.
    EXPECT_GT(error.size(), c.field.size() + 2) << c.label;
    const auto model = MakeCameraModel(c.spec);
    EXPECT_FALSE(model) << c.label;
    if (!model) {
      EXPECT_EQ(model.error(), error) << c.label;
    }
  }
}

TEST(CameraSpec, ValidSpecsPassAndModelNamesRoundTrip) {
  for (const CameraSpec& spec :
       {EurocPinhole(), WidePinholeK3(), Fisheye186(), FisheyeAutomatic(), OcamLike()}) {
    const Status status = spec.Check();
    EXPECT_TRUE(status.ok()) << spec.name << ": " << status.message();
    EXPECT_TRUE(status.message().empty());
  }
  for (const auto model :
       {CameraSpec::Model::kPinhole, CameraSpec::Model::kFisheye, CameraSpec::Model::kScaramuzza}) {
    EXPECT_EQ(ModelFromName(ModelName(model)), model);
  }
  EXPECT_FALSE(ModelFromName("omni"));
  EXPECT_FALSE(ModelFromName("Pinhole"));
}

}  // namespace
}  // namespace rigcal::camera
