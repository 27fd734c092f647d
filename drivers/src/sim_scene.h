#pragma once
// Scene and renderer of the simulated rig: axis-aligned textured planes and boxes and a pipe
// (cylinder along x), procedural mip-mapped textures, and a ray-casting renderer through
// precomputed per-pixel bearings. Private to drivers/.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "rigcal/calib/types.h"
#include "rigcal/drivers/simulated_rig.h"
#include "rigcal/camera/camera_model.h"

namespace rigcal::drivers::internal {

// A square, power-of-two, periodic grey texture with its mip pyramid (2x2 box filtered), in the
// "row pair" layout of the sampler: level l (size n = size >> l) holds n rows of
// n + kTexturePairPad two-byte entries; entry (x, y) is texel (x, y) followed by texel
// (x, y + 1 mod n); entry n of a row repeats entry 0 (the rest of the padding is zero).
inline constexpr int kTexturePairPad = 16;
struct TextureTile {
  int log2_size = 0;
  std::vector<std::vector<uint8_t>> pairs;
  // Texel (x, y) of level l.
  uint8_t At(int l, int x, int y) const {
    const size_t n = size_t{1} << (log2_size - l);
    return pairs[l][2 * (static_cast<size_t>(y) * (n + kTexturePairPad) + static_cast<size_t>(x))];
  }
};

// Scale-invariant "dead leaves" texture: opaque axis-aligned rectangles, rotated rectangles and
// discs of random grey with sizes from 1.5 to size/8 texels (density ~ r^-3), lightly blurred.
// Periodic (tiles seamlessly), deterministic for `seed`.
TextureTile MakeDeadLeavesTile(int log2_size, uint64_t seed);

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

class Scene {
 public:
  // Builds the scene of spec.scene (layout and textures from spec.seed).
  static Scene Build(const SimulatedRigSpec& spec);

  // Casts ray o + t d (d unit, world frame). `pixel_angle`: angle subtended by one pixel along
  // the ray, radians (selects the mip level).
  Hit Cast(const float o[3], const float d[3], float pixel_angle) const;
  // The same, testing only the boxes listed in `boxes` (indices, -1 ends the list early) besides
  // the enclosure or pipe: for rays between rays known to hit only those boxes.
  Hit CastAmong(const float o[3], const float d[3], float pixel_angle, const int* boxes,
                int num_boxes) const;
  // The box a surface belongs to, or -1 (enclosure faces, pipe, sky).
  int BoxOfSurface(int32_t surface) const {
    return has_enclosure_ && surface >= 6 ? (surface - 6) / 6 : -1;
  }
  // First hit distance in units of |d|, double precision; nullopt when the ray hits nothing.
  std::optional<double> Distance(const Eigen::Vector3d& o, const Eigen::Vector3d& d) const;
  // Empty when p is in free space at least `clearance` away from every surface; else what p
  // is too close to or inside of.
  std::string CheckFree(const Eigen::Vector3d& p, double clearance) const;

  // Trilinear texture sample of surface `surface` at level-0 texel coordinates (u, v).
  float Sample(int32_t surface, float u, float v, float lod) const;
  // Adds weight * intensity to the nx x ny pixels of one block (rows `stride` floats apart)
  // whose corner nodes (h00 top-left, h10 top-right, h01 bottom-left, h11 bottom-right, `block`
  // pixels apart) all hit the same surface or all see the sky: texture coordinates and mip
  // level are interpolated bilinearly between the corners.
  void FillBlock(const Hit& h00, const Hit& h10, const Hit& h01, const Hit& h11, int block, int nx,
                 int ny, float weight, float* out, int stride) const;
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

  struct TileView {
    const uint8_t* level[16];
    int num_levels;
  };
  static float SampleTile(const TileView& tile, float u, float v, float lod);

  // First surface along o + t d; `boxes`: null = every box that can be hit (band culling),
  // else only these `num_boxes` boxes.
  template <typename T>
  int32_t Intersect(const T o[3], const T d[3], T* t_hit, const int* boxes = nullptr,
                    int num_boxes = 0) const;
  Hit Shade(const float o[3], const float d[3], float pixel_angle, int32_t surface, float t) const;

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
  std::vector<Surface> surfaces_;
  std::vector<std::shared_ptr<const TextureTile>> tiles_;
  std::vector<TileView> tile_views_;  // per tile: level pointers, for the sampler
};

// Per camera: the unit bearing of every pixel (camera frame, NaN x when the pixel has none)
// and the local pixel angle, computed once.
struct CameraTables {
  std::shared_ptr<const camera::CameraModel> model;
  int width = 0;
  int height = 0;
  std::vector<float> bearings;  // 3 per pixel, row-major
};
CameraTables MakeCameraTables(std::shared_ptr<const camera::CameraModel> model);

// Ray-casting nodes every `block` pixels (block >= 2): node (i, j) sits at pixel
// (i * block, j * block); nodes just beyond the right/bottom edge close the last blocks.
struct NodeGrid {
  int block = 0;
  int nodes_x = 0;
  int nodes_y = 0;
  std::vector<float> bearings;     // 3 per node, NaN x when invalid
  std::vector<float> pixel_angle;  // per node, radians per pixel
};
NodeGrid MakeNodeGrid(const CameraTables& camera, int block);

// Renders the view of `camera` at world_from_camera and adds weight * intensity to acc
// (width * height floats). `grid` null or block < 2: every pixel is cast. `hits`: scratch.
void RenderAccumulate(const Scene& scene, const CameraTables& camera, const NodeGrid* grid,
                      const Pose& world_from_camera, float weight, float* acc,
                      std::vector<Hit>* hits);

}  // namespace rigcal::drivers::internal
