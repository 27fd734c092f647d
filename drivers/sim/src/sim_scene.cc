// SPDX-License-Identifier: Apache-2.0
// Scene of the simulated rig: layout from the spec, description and the free-space check.
#include "sim_scene.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>

#include "sim_random.h"

namespace rigcal::sim::internal {
namespace {

constexpr int kNumTiles = 6;

}  // namespace

Scene Scene::Build(const SimulatedRigSpec& spec) {
  Scene scene;
  const double texel = spec.TexelSize();
  scene.inv_texel_ = static_cast<float>(1.0 / texel);
  const std::vector<SimulatedRigSpec::GreyImage>& photos = spec.scene.textures;
  for (int i = 0; i < kNumTiles; ++i) {
    scene.tiles_.push_back(
        photos.empty()
            ? SharedDeadLeavesTile(kTextureTileLog2, HashKey(spec.seed, kPurposeTexture, i))
            : std::make_shared<const TextureTile>(
                  MakePhotoTile(photos[static_cast<size_t>(i) % photos.size()], kTextureTileLog2)));
  }
  for (const auto& tile : scene.tiles_) scene.tile_views_.push_back(MakeTileView(*tile));
  Rng rng(HashKey(spec.seed, kPurposeLayout));
  const float tile_texels = static_cast<float>(1 << kTextureTileLog2);
  auto add_surface = [&](Kind kind, int tile, float u_period) {
    Surface f;
    f.kind = kind;
    f.tile = tile % kNumTiles;
    f.offset_u = static_cast<float>(rng.Uniform(0, tile_texels));
    f.offset_v = static_cast<float>(rng.Uniform(0, tile_texels));
    f.u_period = u_period;
    scene.surfaces_.push_back(f);
  };

  std::ostringstream description;
  if (spec.scene.type == SimulatedRigSpec::SceneType::kPipe) {
    scene.has_pipe_ = true;
    scene.radius_ = 0.5 * spec.scene.pipe_diameter;
    scene.x0_ = 0.0;
    scene.x1_ = spec.scene.pipe_length;
    add_surface(Kind::kCylinderX, 0, static_cast<float>(2.0 * M_PI * scene.radius_ / texel));
    add_surface(Kind::kPlaneX, 1, 0.f);  // cap at x0
    add_surface(Kind::kPlaneX, 2, 0.f);  // cap at x1
    description << "pipe, diameter " << spec.scene.pipe_diameter << " m, length "
                << spec.scene.pipe_length << " m";
  } else {
    const Eigen::Vector3d size = spec.SceneSize();
    scene.has_enclosure_ = true;
    scene.open_top_ = spec.scene.type != SimulatedRigSpec::SceneType::kRoom;
    scene.lo_[0] = -0.5 * size.x();
    scene.hi_[0] = 0.5 * size.x();
    scene.lo_[1] = -0.5 * size.y();
    scene.hi_[1] = 0.5 * size.y();
    scene.lo_[2] = 0.0;
    scene.hi_[2] = size.z();
    // Enclosure faces: surface 2 * axis + (0: lo, 1: hi).
    const Kind kinds[3] = {Kind::kPlaneX, Kind::kPlaneY, Kind::kPlaneZ};
    for (int face = 0; face < 6; ++face) add_surface(kinds[face / 2], face, 0.f);
    // Boxes along the walls, in the outer 30% of each half-extent.
    for (int b = 0; b < spec.scene.boxes; ++b) {
      const int wall = static_cast<int>(rng.Below(4));  // -x, +x, -y, +y
      const int across = wall / 2;                      // axis perpendicular to the wall
      const int along = 1 - across;
      const double half_across = 0.5 * size[across];
      const double half_along = 0.5 * size[along];
      const double band = 0.3 * half_across;
      const double depth = rng.Uniform(0.3, 1.0) * band;
      const double length = std::min(rng.Uniform(0.3, 1.2) * band, 0.5 * size[along]);
      const double height = rng.Uniform(0.15, 0.7) * size.z();
      const double centre = rng.Uniform(-half_along + 0.5 * length, half_along - 0.5 * length);
      Box box;
      if (wall % 2 == 0) {
        box.lo[across] = -half_across;
        box.hi[across] = -half_across + depth;
      } else {
        box.lo[across] = half_across - depth;
        box.hi[across] = half_across;
      }
      box.lo[along] = centre - 0.5 * length;
      box.hi[along] = centre + 0.5 * length;
      box.lo[2] = 0.0;
      box.hi[2] = height;
      box.first_surface = static_cast<int32_t>(scene.surfaces_.size());
      const int tile = static_cast<int>(rng.Below(kNumTiles));
      for (int face = 0; face < 6; ++face) add_surface(kinds[face / 2], tile + face, 0.f);
      scene.wall_boxes_[wall].push_back(static_cast<int>(scene.boxes_.size()));
      scene.boxes_.push_back(box);
    }
    // Boxes of wall w lie in its band: x <= lo_x + band_x (w = 0), x >= hi_x - band_x (1),
    // likewise in y (2, 3).
    for (int a = 0; a < 2; ++a) {
      const double band = 0.3 * 0.5 * size[a];
      scene.band_[2 * a] = scene.lo_[a] + band;
      scene.band_[2 * a + 1] = scene.hi_[a] - band;
    }
    description << ToString(spec.scene.type) << " " << size.x() << " x " << size.y() << " x "
                << size.z() << " m with " << spec.scene.boxes << " boxes";
    scene.AddMovingBoxes(spec, &description);
  }
  description << ", texel " << texel * 1000.0 << " mm";
  if (!photos.empty()) description << ", textures from " << photos.size() << " photograph(s)";
  scene.description_ = description.str();
  return scene;
}

void Scene::AddMovingBoxes(const SimulatedRigSpec& spec, std::ostringstream* description) {
  const SimulatedRigSpec::Scene::MovingObjects& m = spec.scene.moving_objects;
  if (m.count <= 0) return;
  num_moving_ = m.count;
  moving_half_ = 0.5 * m.size_m;
  first_moving_surface_ = static_cast<int32_t>(surfaces_.size());
  // Their own random numbers, so that the static layout is the same with and without them.
  Rng rng(HashKey(spec.seed, kPurposeMovingTexture));
  const float tile_texels = static_cast<float>(1 << kTextureTileLog2);
  const Kind kinds[3] = {Kind::kPlaneX, Kind::kPlaneY, Kind::kPlaneZ};
  for (int b = 0; b < m.count; ++b) {
    const int tile = static_cast<int>(rng.Below(kNumTiles));
    for (int face = 0; face < 6; ++face) {
      Surface f;
      f.kind = kinds[face / 2];
      f.tile = (tile + face) % kNumTiles;
      f.offset_u = static_cast<float>(rng.Uniform(0, tile_texels));
      f.offset_v = static_cast<float>(rng.Uniform(0, tile_texels));
      surfaces_.push_back(f);
    }
  }
  *description << " and " << m.count << " moving objects " << m.size_m.x() << " x " << m.size_m.y()
               << " x " << m.size_m.z() << " m at " << m.speed_mps << " m/s";
}

std::string Scene::Describe() const { return description_; }

size_t Scene::TextureBytes() const {
  size_t bytes = 0;
  for (const auto& tile : tiles_) {
    for (const auto& level : tile->pairs) bytes += level.size();
  }
  return bytes;
}

Status Scene::CheckFree(const Eigen::Vector3d& p, double clearance) const {
  std::ostringstream out;
  if (has_enclosure_) {
    for (int a = 0; a < 3; ++a) {
      if (p[a] < lo_[a] + clearance || p[a] > hi_[a] - clearance) {
        out << "leaves the " << (open_top_ ? "yard" : "room") << " [" << lo_[0] << ", " << hi_[0]
            << "] x [" << lo_[1] << ", " << hi_[1] << "] x [" << lo_[2] << ", " << hi_[2]
            << "] (clearance " << clearance << " m)";
        return Error{out.str()};
      }
    }
    for (size_t b = 0; b < boxes_.size(); ++b) {
      const Box& box = boxes_[b];
      bool inside = true;
      for (int a = 0; a < 3; ++a) {
        inside = inside && p[a] > box.lo[a] - clearance && p[a] < box.hi[a] + clearance;
      }
      if (inside) {
        out << "enters box " << b << " [" << box.lo[0] << ", " << box.hi[0] << "] x [" << box.lo[1]
            << ", " << box.hi[1] << "] x [" << box.lo[2] << ", " << box.hi[2]
            << "] (boxes stand in the outer 30% of the floor plan)";
        return Error{out.str()};
      }
    }
  }
  if (has_pipe_) {
    const double r = std::hypot(p.y(), p.z());
    if (r > radius_ - clearance || p.x() < x0_ + clearance || p.x() > x1_ - clearance) {
      out << "leaves the pipe (radius " << radius_ << " m along x in [" << x0_ << ", " << x1_
          << "]; distance from the axis " << r << " m)";
      return Error{out.str()};
    }
  }
  return Status::Ok();
}

}  // namespace rigcal::sim::internal
