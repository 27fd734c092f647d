// SPDX-License-Identifier: Apache-2.0
// Camera sections of rig configs and Kalibr camchain files: every model parses, and every error
// names the file, the line and the key.
#include <gtest/gtest.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "../../tools/io/src/config_sections.h"
#include "rigcal/camera/camera_spec.h"
#include "rigcal/io/camera_files.h"

namespace rigcal::io {
namespace {

namespace fs = std::filesystem;
using camera::CameraSpec;

constexpr char kPath[] = "rig.yaml";

// 1-based line of the first line of `text` containing `needle` (0 when absent).
int LineOf(const std::string& text, const std::string& needle) {
  std::istringstream in(text);
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (line.find(needle) != std::string::npos) return number;
  }
  return 0;
}

Expected<CameraSpec> Parse(const std::string& text) {
  return ParseCameraSection(YAML::Load(text), kPath);
}

// The parse fails with "<path>:<line of needle>: <key>: ..." where `what` appears in the rest.
void ExpectError(const std::string& text, const std::string& needle, const std::string& key,
                 const std::string& what = "") {
  SCOPED_TRACE(text);
  const auto spec = Parse(text);
  ASSERT_FALSE(spec);
  const int line = LineOf(text, needle);
  ASSERT_GT(line, 0) << needle;
  const std::string head = std::string(kPath) + ":" + std::to_string(line) + ": " + key + ": ";
  EXPECT_EQ(spec.error().rfind(head, 0), 0u) << "expected prefix '" << head << "' in\n"
                                             << spec.error();
  EXPECT_NE(spec.error().find(what), std::string::npos) << spec.error();
}

const std::string kPinhole =
    "name: cam0\n"
    "model: pinhole\n"
    "resolution: [752, 480]\n"
    "intrinsics: [458.654, 457.296, 367.215, 248.375]\n"
    "distortion: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]\n"
    "nominal: {q_wxyz: [1, 0, 0, 0], C: [0, 0, 0]}\n"
    "truth:\n"
    "  q_wxyz: [1, 0, 0, 0]\n"
    "  C: [0, 0, 0]\n"
    "device: /dev/video0\n";

const std::string kFisheye =
    "name: left\n"
    "model: fisheye\n"
    "resolution: [800, 800]\n"
    "intrinsics: [240, 239, 401, 398]\n"
    "distortion: [0.02, -0.005, 0.001, -0.0001]\n"
    "max_field_angle_deg: 93\n";

const std::string kScaramuzza =
    "name: omni\n"
    "model: scaramuzza\n"
    "resolution: [900, 900]\n"
    "poly: [-230.0, 0.0, 1.2e-3, -1.5e-6, 4e-9]\n"
    "center: [451.3, 448.7]\n"
    "affine: [1.0005, 3e-4, -2e-4]\n"
    "max_field_angle_deg: 93\n";

TEST(CameraYaml, PinholeWithKeysOwnedByOthers) {
  const auto spec = Parse(kPinhole);
  ASSERT_TRUE(spec) << spec.error();
  EXPECT_EQ(spec->name, "cam0");
  EXPECT_EQ(spec->model, CameraSpec::Model::kPinhole);
  EXPECT_EQ(spec->width, 752);
  EXPECT_EQ(spec->height, 480);
  EXPECT_EQ(spec->intrinsics, (std::array<double, 4>{458.654, 457.296, 367.215, 248.375}));
  EXPECT_EQ(spec->distortion,
            (std::vector<double>{-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05}));
  EXPECT_EQ(spec->max_field_angle_deg, 0.0);
  EXPECT_TRUE(spec->poly.empty());
  auto model = camera::MakeCameraModel(*spec);
  ASSERT_TRUE(model) << model.error();
  EXPECT_EQ((*model)->type(), "pinhole");
}

TEST(CameraYaml, PinholeWithK3AndWithoutDistortion) {
  auto text = kPinhole;
  text.replace(text.find("1.76187114e-05]"), 15, "1.76187114e-05, -0.001]");
  auto spec = Parse(text);
  ASSERT_TRUE(spec) << spec.error();
  ASSERT_EQ(spec->distortion.size(), 5u);
  EXPECT_EQ(spec->distortion[4], -0.001);

  text = kPinhole;
  text.erase(text.find("distortion:"), text.find("nominal:") - text.find("distortion:"));
  spec = Parse(text);
  ASSERT_TRUE(spec) << spec.error();
  EXPECT_TRUE(spec->distortion.empty());
}

TEST(CameraYaml, RollingShutterReadout) {
  auto spec = Parse(kPinhole + "rolling_shutter_ms: 30\n");
  ASSERT_TRUE(spec) << spec.error();
  EXPECT_DOUBLE_EQ(spec->rolling_shutter_s, 0.03);
  auto model = camera::MakeCameraModel(*spec);
  ASSERT_TRUE(model) << model.error();
  EXPECT_DOUBLE_EQ((*model)->rolling_shutter_s(), 0.03);
  EXPECT_DOUBLE_EQ((*model)->Clone()->rolling_shutter_s(), 0.03);
  // Without the key: a global shutter.
  spec = Parse(kPinhole);
  ASSERT_TRUE(spec) << spec.error();
  EXPECT_EQ(spec->rolling_shutter_s, 0.0);
  ExpectError(kPinhole + "rolling_shutter_ms: -1\n",
              "rolling_shutter_ms:", "cam0.rolling_shutter_ms", "[0, 1000) ms");
  ExpectError(kPinhole + "rolling_shutter_ms: slow\n",
              "rolling_shutter_ms:", "cam0.rolling_shutter_ms", "not a number");
}

TEST(CameraYaml, Fisheye) {
  const auto spec = Parse(kFisheye);
  ASSERT_TRUE(spec) << spec.error();
  EXPECT_EQ(spec->model, CameraSpec::Model::kFisheye);
  EXPECT_EQ(spec->distortion, (std::vector<double>{0.02, -0.005, 0.001, -0.0001}));
  EXPECT_EQ(spec->max_field_angle_deg, 93.0);
  auto model = camera::MakeCameraModel(*spec);
  ASSERT_TRUE(model) << model.error();
  EXPECT_DOUBLE_EQ((*model)->MaxFieldAngleDeg(), 93.0);
}

TEST(CameraYaml, Scaramuzza) {
  auto spec = Parse(kScaramuzza);
  ASSERT_TRUE(spec) << spec.error();
  EXPECT_EQ(spec->model, CameraSpec::Model::kScaramuzza);
  EXPECT_EQ(spec->poly, (std::vector<double>{-230.0, 0.0, 1.2e-3, -1.5e-6, 4e-9}));
  EXPECT_EQ(spec->center, (std::array<double, 2>{451.3, 448.7}));
  EXPECT_EQ(spec->affine, (std::array<double, 3>{1.0005, 3e-4, -2e-4}));
  EXPECT_TRUE(spec->inverse_poly.empty());
  EXPECT_EQ(spec->intrinsics, (std::array<double, 4>{0, 0, 0, 0}));
  auto model = camera::MakeCameraModel(*spec);
  ASSERT_TRUE(model) << model.error();
  EXPECT_EQ((*model)->type(), "scaramuzza");

  // Affine omitted: identity.
  std::string text = kScaramuzza;
  text.erase(text.find("affine:"), text.find("max_field") - text.find("affine:"));
  spec = Parse(text);
  ASSERT_TRUE(spec) << spec.error();
  EXPECT_EQ(spec->affine, (std::array<double, 3>{1.0, 0.0, 0.0}));
}

TEST(CameraYaml, EquidistantScaramuzzaSpecSurvivesTheConfig) {
  // The poly of ScaramuzzaSpecForEquidistant written with 17 digits parses to the same model.
  auto spec = camera::ScaramuzzaSpecForEquidistant("omni", 800, 800, 240.0, 399.5, 400.5, 93.0);
  ASSERT_TRUE(spec) << spec.error();
  std::ostringstream text;
  text.precision(17);
  text << "name: omni\nmodel: scaramuzza\nresolution: [800, 800]\npoly: [";
  for (size_t i = 0; i < spec->poly.size(); ++i) text << (i ? ", " : "") << spec->poly[i];
  text << "]\ncenter: [399.5, 400.5]\nmax_field_angle_deg: 93\n";
  const auto parsed = Parse(text.str());
  ASSERT_TRUE(parsed) << parsed.error();
  EXPECT_EQ(parsed->poly, spec->poly);
  auto a = camera::MakeCameraModel(*spec);
  auto b = camera::MakeCameraModel(*parsed);
  ASSERT_TRUE(a && b);
  const Eigen::Vector3d point(0.9, -0.4, -0.02);  // behind the image plane, inside 93 degrees
  EXPECT_EQ(*(*a)->Project(point), *(*b)->Project(point));

  // The exact inverse of the ideal lens, rho = f (phi + pi / 2), given in block style.
  const std::string with_inverse = text.str() + "inverse_poly:\n  - 376.99111843077515\n  - 240\n";
  const auto inverse = Parse(with_inverse);
  ASSERT_TRUE(inverse) << inverse.error();
  EXPECT_EQ(inverse->inverse_poly, (std::vector<double>{376.99111843077515, 240.0}));
  // The same in degrees (a convention mistake) is off by hundreds of pixels.
  std::string degrees = with_inverse;
  degrees.replace(degrees.find("  - 240\n"), 8, "  - 13750.987\n");
  ExpectError(degrees, "inverse_poly:", "omni.inverse_poly", "does not invert poly");
}

TEST(CameraYaml, ErrorsNameTheLineAndTheKey) {
  std::string text;

  text = kPinhole;
  text.erase(text.find("model: pinhole\n"), 15);
  ExpectError(text, "name: cam0", "cam0.model", "missing");

  text = kPinhole;
  text.replace(text.find("model: pinhole"), 14, "model: omni");
  ExpectError(text, "model: omni", "cam0.model", "'omni' is not a camera model");

  text = kPinhole;
  text.erase(text.find("intrinsics:"), text.find("distortion:") - text.find("intrinsics:"));
  ExpectError(text, "name: cam0", "cam0.intrinsics", "missing");

  text = kPinhole;
  text.replace(text.find("[458.654, 457.296, 367.215, 248.375]"), 36,
               "[458.654, 457.296, 367.215]");
  ExpectError(text, "intrinsics:", "cam0.intrinsics", "expected 4 numbers, got 3");

  text = kPinhole;
  text.replace(text.find("0.07395907"), 10, "abc");
  ExpectError(text, "distortion:", "cam0.distortion[1]", "'abc' is not a number");

  text = kPinhole;
  text.replace(text.find("[-0.28340811"), 1, "[1, 2, ");
  ExpectError(text, "distortion:", "cam0.distortion", "got 6 values");

  text = kPinhole + "distorsion: [0, 0, 0, 0]\n";
  ExpectError(text, "distorsion:", "cam0.distorsion", "unknown key");

  text = kPinhole + "poly: [-200, 0, 0.001]\n";
  ExpectError(text, "poly:", "cam0.poly", "not used by model pinhole");

  text = kPinhole;
  text.replace(text.find("[752, 480]"), 10, "[752.5, 480]");
  ExpectError(text, "resolution:", "cam0.resolution[0]", "not an integer");

  text = kPinhole;
  text.replace(text.find("[458.654,"), 9, "[-458.654,");
  ExpectError(text, "intrinsics:", "cam0.intrinsics", "fx and fy must be > 0");

  text = kPinhole;
  text.replace(text.find("367.215"), 7, "967.215");
  ExpectError(text, "intrinsics:", "cam0.intrinsics", "outside");

  text = kFisheye;
  text.replace(text.find("0.02, -0.005"), 12, "-0.5, 0.0");
  ExpectError(text, "max_field_angle_deg:", "left.max_field_angle_deg", "folds back");

  text = kFisheye;
  text.replace(text.find("[0.02, -0.005, 0.001, -0.0001]"), 30, "[0.02, -0.005, 0.001]");
  ExpectError(text, "distortion:", "left.distortion", "[k1, k2, k3, k4]");

  text = kFisheye + "max_field_angle_deg_typo: 3\n";
  ExpectError(text, "max_field_angle_deg_typo", "left.max_field_angle_deg_typo", "unknown key");

  text = kScaramuzza;
  text.erase(text.find("center:"), text.find("affine:") - text.find("center:"));
  ExpectError(text, "name: omni", "omni.center", "missing");

  text = kScaramuzza;
  text.replace(text.find("[-230.0"), 7, "[230.0");
  ExpectError(text, "poly:", "omni.poly", "a0 must be < 0");

  text = kScaramuzza;
  text.replace(text.find("[1.0005, 3e-4, -2e-4]"), 21, "[1.0005, 3e-4]");
  ExpectError(text, "affine:", "omni.affine", "expected 3 numbers");

  text = kScaramuzza + "intrinsics: [230, 230, 450, 450]\n";
  ExpectError(text, "intrinsics:", "omni.intrinsics", "not used by model scaramuzza");

  text = kScaramuzza;
  text.replace(text.find(", 4e-9]"), 7, "]");  // the field angle then peaks near 79 deg
  ExpectError(text, "max_field_angle_deg:", "omni.max_field_angle_deg", "stops increasing");

  text = kScaramuzza;
  text.replace(text.find("max_field_angle_deg: 93"), 23, "max_field_angle_deg: wide");
  ExpectError(text, "max_field_angle_deg:", "omni.max_field_angle_deg", "not a number");

  // A camera entry that is not a map, and one without a name.
  EXPECT_FALSE(Parse("[1, 2]"));
  ExpectError("model: pinhole\nresolution: [1, 1]\n", "model: pinhole", "name", "missing");
}

// ------------------------------------------------------------------------------------------
// Kalibr camchain files

std::string WriteTemp(const std::string& text) {
  static int counter = 0;
  const fs::path path =
      fs::temp_directory_path() /
      ("rigcal_camchain_" + std::to_string(::getpid()) + "_" + std::to_string(counter++) + ".yaml");
  std::ofstream(path) << text;
  return path.string();
}

// A camchain as Kalibr writes it, with the EuRoC MAV intrinsics
// (shared/data/euroc_v101_static/mav0/cam{0,1}/sensor.yaml).
const std::string kCamchain =
    "cam0:\n"
    "  cam_overlaps: [1]\n"
    "  camera_model: pinhole\n"
    "  distortion_coeffs: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]\n"
    "  distortion_model: radtan\n"
    "  intrinsics: [458.654, 457.296, 367.215, 248.375]\n"
    "  resolution: [752, 480]\n"
    "  rostopic: /cam0/image_raw\n"
    "cam1:\n"
    "  T_cn_cnm1:\n"
    "  - [0.9999972564, 0.0022312131, 0.0003760255, -0.1100738695]\n"
    "  - [-0.0022317275, 0.9999955595, 0.0013807009, 0.0003991693]\n"
    "  - [-0.0003729484, -0.0013815362, 0.9999989761, -0.0008538499]\n"
    "  - [0.0, 0.0, 0.0, 1.0]\n"
    "  cam_overlaps: [0]\n"
    "  camera_model: pinhole\n"
    "  distortion_coeffs: [-0.28368365, 0.07451284, -0.00010473, -3.555907e-05]\n"
    "  distortion_model: radtan\n"
    "  intrinsics: [457.587, 456.134, 379.999, 255.238]\n"
    "  resolution: [752, 480]\n"
    "  rostopic: /cam1/image_raw\n"
    "  rigcal_name: right\n";

TEST(KalibrCamchain, EurocPinholeRadtan) {
  const auto specs = ReadKalibrIntrinsics(WriteTemp(kCamchain));
  ASSERT_TRUE(specs) << specs.error();
  ASSERT_EQ(specs->size(), 2u);
  const CameraSpec& cam0 = (*specs)[0];
  const CameraSpec& cam1 = (*specs)[1];
  EXPECT_EQ(cam0.name, "cam0");
  EXPECT_EQ(cam1.name, "right");
  EXPECT_EQ(cam0.model, CameraSpec::Model::kPinhole);
  EXPECT_EQ(cam0.width, 752);
  EXPECT_EQ(cam0.height, 480);
  EXPECT_EQ(cam0.intrinsics, (std::array<double, 4>{458.654, 457.296, 367.215, 248.375}));
  EXPECT_EQ(cam1.distortion,
            (std::vector<double>{-0.28368365, 0.07451284, -0.00010473, -3.555907e-05}));
  for (const CameraSpec& spec : *specs) {
    auto model = camera::MakeCameraModel(spec);
    ASSERT_TRUE(model) << model.error();
    const Eigen::Vector2d corner(0.0, 0.0);
    const auto bearing = (*model)->Unproject(corner);
    ASSERT_TRUE(bearing);
    EXPECT_LE((*(*model)->Project(*bearing) - corner).norm(), 1e-9);
  }
}

TEST(KalibrCamchain, EquidistantIsFisheyeAndNoneIsUndistorted) {
  std::string text = kCamchain;
  text.replace(text.find("distortion_model: radtan"), 24, "distortion_model: equidistant");
  text.replace(text.find("[-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]"), 53,
               "[-0.0036, 0.0074, -0.0096, 0.0030]");
  auto specs = ReadKalibrIntrinsics(WriteTemp(text));
  ASSERT_TRUE(specs) << specs.error();
  EXPECT_EQ((*specs)[0].model, CameraSpec::Model::kFisheye);
  EXPECT_EQ((*specs)[0].distortion, (std::vector<double>{-0.0036, 0.0074, -0.0096, 0.0030}));
  EXPECT_EQ((*specs)[1].model, CameraSpec::Model::kPinhole);

  text = kCamchain;
  text.replace(text.find("distortion_model: radtan"), 24, "distortion_model: none");
  text.replace(text.find("[-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]"), 53, "[]");
  specs = ReadKalibrIntrinsics(WriteTemp(text));
  ASSERT_TRUE(specs) << specs.error();
  EXPECT_EQ((*specs)[0].model, CameraSpec::Model::kPinhole);
  EXPECT_TRUE((*specs)[0].distortion.empty());
}

void ExpectKalibrError(const std::string& text, const std::string& needle, const std::string& key,
                       const std::string& what) {
  SCOPED_TRACE(text);
  const std::string path = WriteTemp(text);
  const auto specs = ReadKalibrIntrinsics(path);
  ASSERT_FALSE(specs);
  const int line = LineOf(text, needle);
  ASSERT_GT(line, 0) << needle;
  const std::string head = path + ":" + std::to_string(line) + ": " + key + ": ";
  EXPECT_EQ(specs.error().rfind(head, 0), 0u) << "expected prefix '" << head << "' in\n"
                                              << specs.error();
  EXPECT_NE(specs.error().find(what), std::string::npos) << specs.error();
}

TEST(KalibrCamchain, UnsupportedModelsAndBadValuesAreErrorsWithLines) {
  std::string text = kCamchain;
  // Kalibr omni: camera_model omni with 5 intrinsics (xi, fu, fv, pu, pv).
  text.replace(text.find("camera_model: pinhole\n  distortion_coeffs: [-0.28368365"), 21,
               "camera_model: omni");
  text.replace(text.find("[457.587,"), 9, "[0.9, 457.587,");
  ExpectKalibrError(text, "camera_model: omni", "cam1.camera_model",
                    "camera right: Kalibr model 'omni'");

  for (const std::string model : {"ds", "eucm"}) {
    text = kCamchain;
    text.replace(text.find("camera_model: pinhole"), 21, "camera_model: " + model);
    ExpectKalibrError(text, "camera_model: " + model, "cam0.camera_model",
                      "camera cam0: Kalibr model '" + model + "'");
  }

  text = kCamchain;
  text.replace(text.find("distortion_model: radtan"), 24, "distortion_model: fov");
  ExpectKalibrError(text, "distortion_model: fov", "cam0.distortion_model",
                    "camera cam0: Kalibr model pinhole-fov is not supported");

  text = kCamchain;
  text.erase(text.find("  intrinsics: [458.654"),
             text.find("  resolution: [752, 480]\n  rostopic: /cam0") -
                 text.find("  intrinsics: [458.654"));
  ExpectKalibrError(text, "cam0:", "cam0.intrinsics", "missing");

  text = kCamchain;
  text.replace(text.find("[-0.28368365, 0.07451284,"), 25, "[0.07451284,");
  ExpectKalibrError(text, "distortion_coeffs: [0.07451284", "cam1.distortion_coeffs",
                    "expected 4 numbers, got 3");

  text = kCamchain;
  text.replace(text.find("[457.587, 456.134"), 17, "[457.587, x");
  ExpectKalibrError(text, "intrinsics: [457.587", "cam1.intrinsics[1]", "'x' is not a number");

  text = kCamchain;
  text.replace(text.find("[457.587,"), 9, "[-457.587,");
  ExpectKalibrError(text, "intrinsics: [-457.587", "cam1.intrinsics", "fx and fy must be > 0");

  text = kCamchain;
  text.replace(text.find("cam1:"), 5, "cam2:");
  ExpectKalibrError(text, "cam2:", "cam2", "cam1 is missing");

  text = kCamchain + "imu0: {}\n";
  ExpectKalibrError(text, "imu0:", "imu0", "unknown key");

  text = kCamchain;
  text.replace(text.find("rigcal_name: right"), 18, "rigcal_name: cam0");
  ExpectKalibrError(text, "rigcal_name: cam0", "cam1.rigcal_name", "duplicate");

  const auto missing = ReadKalibrIntrinsics("/nonexistent/camchain.yaml");
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().find("/nonexistent/camchain.yaml"), std::string::npos);
}

}  // namespace
}  // namespace rigcal::io
