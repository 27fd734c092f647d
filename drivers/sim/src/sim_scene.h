// SPDX-License-Identifier: Apache-2.0
#pragma once
// Scene of the simulated rig: axis-aligned textured planes and boxes and a pipe (cylinder along
// x), built from the spec; ray casting against it (sim_ray_cast.cc) and the free-space check of
// the trajectory. The moving objects' boxes (their shape and texture; where they are when:
// sim_moving_objects.h) are cast against when the caller says where they are. Private to
// rigcal_sim.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/sim/simulated_rig.h"
#include "sim_texture.h"
#include "sim_texture_sampling.h"

namespace rigcal::sim::internal {

inline constexpr int32_t kSky = -1;      // the ray leaves the scene (sky)
inline constexpr int32_t kInvalid = -2;  // no valid bearing at this pixel (outside the lens)

// Result of casting one ray: the surface hit, its texture coordinates in level-0 texels
// (continuous, not wrapped) and the mip level. For kSky, `u` is the sky intensity.
struct Hit {
  int32_t surface = kSky;
  float u = 0.f;
  float v = 0.f;
  float lod = 0.f;
};

// The moving boxes a view casts against: every box's centre at the ray's time (3 floats per box,
// world, m) and the boxes that may be in view (indices into them; the others are not tested).
struct MovingBoxes {
  const float* centres = nullptr;
  const int* visible = nullptr;
  int num_visible = 0;
};

class Scene {
 public:
  // Builds the scene of spec.scene (layout and textures from spec.seed).
  static Scene Build(const SimulatedRigSpec& spec);

  // Casts ray o + t d (d unit, world frame) into the static scene. `pixel_angle`: angle
  // subtended by one pixel along the ray, radians (selects the mip level).
  Hit Cast(const float o[3], const float d[3], float pixel_angle) const;
  // The same with the moving boxes `moving` (where they are at the ray's time); a moving box's
  // texture moves with it.
  Hit Cast(const float o[3], const float d[3], float pixel_angle, const MovingBoxes& moving) const;
  // The same, testing only the static boxes listed in `boxes` (indices, -1 ends the list early)
  // besides the enclosure or pipe (and every moving box): for rays between rays known to hit
  // only those static boxes.
  Hit CastAmong(const float o[3], const float d[3], float pixel_angle, const int* boxes,
                int num_boxes) const;
  Hit CastAmong(const float o[3], const float d[3], float pixel_angle, const int* boxes,
                int num_boxes, const MovingBoxes& moving) const;
  // The static box a surface belongs to, or -1 (enclosure faces, pipe, moving boxes, sky).
  int BoxOfSurface(int32_t surface) const {
    return has_enclosure_ && surface >= 6 && surface < first_moving_surface_ ? (surface - 6) / 6
                                                                             : -1;
  }
  // Number of moving boxes (spec.scene.moving_objects.count) and the radius of the sphere
  // around each (m).
  int MovingBoxCount() const { return num_moving_; }
  double MovingBoxRadius() const { return moving_half_.norm(); }
  // First hit distance in units of |d|, double precision; nullopt when the ray hits nothing.
  std::optional<double> Distance(const Eigen::Vector3d& o, const Eigen::Vector3d& d) const;
  // Ok when p is in free space at least `clearance` away from every surface; else an error
  // saying what p is too close to or inside of ("leaves the room [...]", "enters box 3 [...]").
  Status CheckFree(const Eigen::Vector3d& p, double clearance) const;

  // The texture of surface `surface` (>= 0), sampled at the Hit's texture coordinates.
  const TileView& Texture(int32_t surface) const { return tile_views_[surfaces_[surface].tile]; }
  // Texture coordinate period along u of a surface (0: none). A block whose corners span more
  // than half of it straddles a seam and must not be interpolated.
  float UPeriod(int32_t surface) const { return surfaces_[surface].u_period; }

  std::string Describe() const;
  size_t TextureBytes() const;

 private:
  enum class Kind : uint8_t { kPlaneX, kPlaneY, kPlaneZ, kCylinderX };
  struct Surface {
    Kind kind = Kind::kPlaneZ;
    int tile = 0;
    float offset_u = 0.f;
    float offset_v = 0.f;
    float u_period = 0.f;
  };
  struct Box {
    double lo[3];
    double hi[3];
    int32_t first_surface;  // + 2 * axis + (0: lo face, 1: hi face)
  };

  // First surface along o + t d; `boxes`: null = every box that can be hit (band culling),
  // else only these `num_boxes` boxes.
  template <typename T>
  int32_t Intersect(const T o[3], const T d[3], T* t_hit, const int* boxes = nullptr,
                    int num_boxes = 0) const;
  // The steps of Intersect: each lowers *best (distance) and sets *surface when it finds a
  // nearer surface. The enclosure's faces (its top is the sky in a yard), then its boxes
  // (`exit`: x, y where the ray leaves the enclosure); the pipe's wall or caps.
  template <typename T>
  void IntersectEnclosure(const T o[3], const T d[3], const int* boxes, int num_boxes, T* best,
                          int32_t* surface) const;
  template <typename T>
  void IntersectBoxes(const T o[3], const T d[3], const T exit[2], const int* boxes, int num_boxes,
                      T* best, int32_t* surface) const;
  template <typename T>
  void IntersectPipe(const T o[3], const T d[3], T* best, int32_t* surface) const;
  // The nearest of the moving boxes along o + t d nearer than *best: lowers *best, sets
  // *surface and returns the box's index; -1 when none is nearer.
  int IntersectMoving(const float o[3], const float d[3], const MovingBoxes& moving, float* best,
                      int32_t* surface) const;
  // Shade of the nearer of the static hit (surface, t) and the moving boxes.
  Hit ShadeWithMoving(const float o[3], const float d[3], float pixel_angle, int32_t surface,
                      float t, const MovingBoxes& moving) const;
  Hit Shade(const float o[3], const float d[3], float pixel_angle, int32_t surface, float t) const;
  // Build's step for spec.scene.moving_objects: their surfaces after every static one.
  void AddMovingBoxes(const SimulatedRigSpec& spec, std::ostringstream* description);

  std::string description_;
  float inv_texel_ = 100.f;
  // Enclosure (room / yard / street), seen from inside.
  bool has_enclosure_ = false;
  bool open_top_ = false;
  double lo_[3] = {0, 0, 0};
  double hi_[3] = {0, 0, 0};
  std::vector<Box> boxes_;
  std::vector<int> wall_boxes_[4];  // boxes along wall -x, +x, -y, +y
  double band_[4] = {0, 0, 0, 0};   // inner edge of each wall's band: x, x, y, y
  // Pipe along x through y = z = 0, seen from inside, with caps at x0 and x1.
  bool has_pipe_ = false;
  double radius_ = 0.3;
  double x0_ = 0.0;
  double x1_ = 1.0;
  // Moving boxes: num_moving_ boxes of half extent moving_half_, centred on the centres the
  // caller gives; box i's faces are surfaces first_moving_surface_ + 6 i + 2 axis + (0: lo,
  // 1: hi), textured in the box's own frame.
  int num_moving_ = 0;
  Eigen::Vector3d moving_half_ = Eigen::Vector3d::Zero();
  int32_t first_moving_surface_ = INT32_MAX;
  std::vector<Surface> surfaces_;
  std::vector<std::shared_ptr<const TextureTile>> tiles_;
  std::vector<TileView> tile_views_;  // per tile: level pointers, for the sampler
};

}  // namespace rigcal::sim::internal
