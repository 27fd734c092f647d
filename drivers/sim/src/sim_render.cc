// SPDX-License-Identifier: Apache-2.0
// Rendering of the simulated rig: bearing tables, node grids, and a view rendered by ray casting
// at the nodes and filling texture blocks between them.
#include "sim_render.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <optional>

#include "sim_texture_sampling.h"

namespace rigcal::sim::internal {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// A rigid transform in float: rotation r (row-major) and translation o (for world_from_camera:
// the camera centre).
struct Transform {
  float r[9];
  float o[3];
  void Apply(const float* b, float* d) const {
    d[0] = r[0] * b[0] + r[1] * b[1] + r[2] * b[2];
    d[1] = r[3] * b[0] + r[4] * b[1] + r[5] * b[2];
    d[2] = r[6] * b[0] + r[7] * b[1] + r[8] * b[2];
  }
};

// Adds weight * intensity to the nx x ny pixels of one block (rows `stride` floats apart)
// whose corner nodes (h00 top-left, h10 top-right, h01 bottom-left, h11 bottom-right, `block`
// pixels apart) all hit the same surface or all see the sky: texture coordinates and mip
// level (or the sky's intensity) are interpolated bilinearly between the corners.
void FillBlock(const Scene& scene, const Hit& h00, const Hit& h10, const Hit& h01, const Hit& h11,
               int block, int nx, int ny, float weight, float* out, int stride,
               RenderKernel kernel) {
  if (h00.surface == kSky) {  // u holds the sky's intensity
    const Bilinear2d u(h00.u, h10.u, h01.u, h11.u, 1.f / static_cast<float>(block));
    for (int y = 0; y < ny; ++y, out += stride) {
      const float start = u.a + static_cast<float>(y) * u.c;
      const float step = u.b + static_cast<float>(y) * u.d;
      for (int x = 0; x < nx; ++x) out[x] += weight * (start + static_cast<float>(x) * step);
    }
    return;
  }
  const BlockCorners corners = {{h00.u, h10.u, h01.u, h11.u},
                                {h00.v, h10.v, h01.v, h11.v},
                                {h00.lod, h10.lod, h01.lod, h11.lod}};
  FillTexturedBlock(scene.Texture(h00.surface), corners, block, nx, ny, weight, out, stride,
                    kernel);
}

Transform WorldFromCameraTransform(const Pose& world_from_camera) {
  Transform xf;
  const Eigen::Matrix3d r = world_from_camera.R();
  for (int i = 0; i < 9; ++i) xf.r[i] = static_cast<float>(r(i / 3, i % 3));
  for (int i = 0; i < 3; ++i) xf.o[i] = static_cast<float>(world_from_camera.C[i]);
  return xf;
}

// world_from_camera and the moving boxes' centres per pixel row: one of each for every row
// (global shutter), or one per row of [0, num_rows) (rolling shutter); and the moving boxes the
// camera may see.
class RowTransforms {
 public:
  RowTransforms(const Pose& world_from_camera, const float* moving, int num_moving)
      : rows_{WorldFromCameraTransform(world_from_camera)},
        num_moving_(moving != nullptr ? num_moving : 0),
        moving_(moving) {}
  RowTransforms(const RowPose& world_from_camera_at_row, const RowMoving& moving_at_row,
                int num_moving, int num_rows)
      : num_moving_(moving_at_row ? num_moving : 0) {
    rows_.reserve(static_cast<size_t>(num_rows));
    for (int y = 0; y < num_rows; ++y) {
      rows_.push_back(WorldFromCameraTransform(world_from_camera_at_row(y)));
    }
    if (num_moving_ == 0) return;
    moving_rows_.resize(3 * static_cast<size_t>(num_moving_) * num_rows);
    for (int y = 0; y < num_rows; ++y) moving_at_row(y, MovingRow(y));
    moving_ = moving_rows_.data();
  }
  const Transform& operator[](int row) const {
    return rows_.size() == 1 ? rows_[0] : rows_[static_cast<size_t>(row)];
  }
  bool has_moving() const { return num_moving_ > 0; }
  // The moving boxes while row `row` is exposed (has_moving()).
  MovingBoxes Moving(int row) const {
    const size_t offset = rows_.size() == 1 ? 0 : 3 * static_cast<size_t>(num_moving_) * row;
    return {moving_ + offset, visible_.data(), static_cast<int>(visible_.size())};
  }
  // Keeps the moving boxes whose bounding sphere (`radius`, m) reaches into the cone of
  // `max_axis_angle` (radians) around the optical axis, or holds the camera centre, at some row.
  void CullMoving(double radius, double max_axis_angle) {
    visible_.clear();
    for (int b = 0; b < num_moving_; ++b) {
      for (size_t y = 0; y < rows_.size(); ++y) {
        if (MaySee(rows_[y], moving_ + 3 * (num_moving_ * y + b), radius, max_axis_angle)) {
          visible_.push_back(b);
          break;
        }
      }
    }
  }

 private:
  float* MovingRow(int row) {
    return moving_rows_.data() + 3 * static_cast<size_t>(num_moving_) * row;
  }
  // Whether a sphere at `centre` of `radius` reaches into the camera's cone: its angle from the
  // axis less its angular radius is at most the cone's.
  static bool MaySee(const Transform& xf, const float* centre, double radius,
                     double max_axis_angle) {
    const Eigen::Vector3d v(centre[0] - xf.o[0], centre[1] - xf.o[1], centre[2] - xf.o[2]);
    const double distance = v.norm();
    if (distance <= radius) return true;
    const double sphere = std::asin(radius / distance);
    if (max_axis_angle + sphere >= M_PI) return true;
    const Eigen::Vector3d axis(xf.r[2], xf.r[5], xf.r[8]);  // the camera's z in the world
    return v.dot(axis) >= distance * std::cos(max_axis_angle + sphere);
  }

  std::vector<Transform> rows_;
  int num_moving_ = 0;
  const float* moving_ = nullptr;
  std::vector<float> moving_rows_;
  std::vector<int> visible_;
};

// Casts single pixels of one camera's view: the pixel's bearing (CameraTables) turned into the
// world, its local pixel angle, and the intensity of what it hits (with the scene's moving boxes
// where the row transforms place them).
class PixelCaster {
 public:
  PixelCaster(const Scene& scene, const CameraTables& camera,
              const RowTransforms& world_from_camera)
      : scene_(scene), camera_(camera), xf_(world_from_camera) {}

  int width() const { return camera_.width; }
  int height() const { return camera_.height; }

  // Intensity seen by pixel (x, y); `boxes`: null, or the only boxes the ray may hit (besides
  // the enclosure or pipe).
  float Cast(int x, int y, const int* boxes, int num_boxes) const {
    const int w = camera_.width;
    const int h = camera_.height;
    const float* b = &camera_.bearings[3 * (static_cast<size_t>(y) * w + x)];
    if (b[0] != b[0]) return 0.f;
    // Local pixel angle as for the nodes: the larger of the chords to the next pixel right and
    // down (the previous one at the last column / row).
    const ptrdiff_t row = 3 * static_cast<ptrdiff_t>(w);
    float pixel_angle = 0.f;
    for (const float* nb : {x + 1 < w ? b + 3 : b - 3, y + 1 < h ? b + row : b - row}) {
      if (nb[0] != nb[0]) continue;
      const float dx = nb[0] - b[0], dy = nb[1] - b[1], dz = nb[2] - b[2];
      pixel_angle = std::max(pixel_angle, std::sqrt(dx * dx + dy * dy + dz * dz));
    }
    if (pixel_angle <= 0.f) pixel_angle = 1e-3f;
    const Transform& xf = xf_[y];
    float d[3];
    xf.Apply(b, d);
    if (xf_.has_moving()) {
      const MovingBoxes moving = xf_.Moving(y);
      return Shade(boxes != nullptr
                       ? scene_.CastAmong(xf.o, d, pixel_angle, boxes, num_boxes, moving)
                       : scene_.Cast(xf.o, d, pixel_angle, moving));
    }
    return Shade(boxes != nullptr ? scene_.CastAmong(xf.o, d, pixel_angle, boxes, num_boxes)
                                  : scene_.Cast(xf.o, d, pixel_angle));
  }

  // Adds weight * intensity of every pixel of columns [x0, x1) and rows [y0, y1) to acc (rows
  // of camera.width floats).
  void AddRays(int x0, int x1, int y0, int y1, const int* boxes, int num_boxes, float weight,
               float* acc) const {
    for (int y = y0; y < y1; ++y) {
      float* row = acc + static_cast<size_t>(y) * camera_.width;
      for (int x = x0; x < x1; ++x) row[x] += weight * Cast(x, y, boxes, num_boxes);
    }
  }

 private:
  float Shade(const Hit& hit) const {
    if (hit.surface == kInvalid) return 0.f;
    if (hit.surface == kSky) return hit.u;
    return SampleTrilinear(scene_.Texture(hit.surface), hit.u, hit.v, hit.lod);
  }

  const Scene& scene_;
  const CameraTables& camera_;
  const RowTransforms& xf_;
};

// Casts the ray of every node of `grid` into `hits` (node order; kInvalid where a node has no
// bearing); node row j from the transform of pixel row j * block.
void CastNodes(const Scene& scene, const NodeGrid& grid, const RowTransforms& xf,
               std::vector<Hit>* hits) {
  hits->resize(static_cast<size_t>(grid.nodes_x) * grid.nodes_y);
  for (size_t k = 0; k < hits->size(); ++k) {
    const float* b = &grid.bearings[3 * k];
    if (b[0] != b[0]) {
      (*hits)[k].surface = kInvalid;
      continue;
    }
    const int row = static_cast<int>(k / grid.nodes_x) * grid.block;
    const Transform& row_xf = xf[row];
    float d[3];
    row_xf.Apply(b, d);
    (*hits)[k] = xf.has_moving() ? scene.Cast(row_xf.o, d, grid.pixel_angle[k], xf.Moving(row))
                                 : scene.Cast(row_xf.o, d, grid.pixel_angle[k]);
  }
}

// Whether a block's corners see one surface (or all the sky, or all nothing) such that texture
// coordinates may be interpolated between them: on a surface with a u period (the pipe's
// seam), the corners must also span less than half of it.
bool IsUniformBlock(const Scene& scene, const Hit& h00, const Hit& h10, const Hit& h01,
                    const Hit& h11) {
  const int32_t s = h00.surface;
  bool uniform = s == h10.surface && s == h01.surface && s == h11.surface;
  if (uniform && s >= 0) {
    const float period = scene.UPeriod(s);
    if (period > 0.f) {
      const float u_min = std::min(std::min(h00.u, h10.u), std::min(h01.u, h11.u));
      const float u_max = std::max(std::max(h00.u, h10.u), std::max(h01.u, h11.u));
      uniform = u_max - u_min < 0.5f * period;
    }
  }
  return uniform;
}

// The boxes the corners of a block hit, into `boxes` (each once), and their number; -1 when a
// corner hits no surface (sky, no bearing), so that a ray between them may hit any box.
int CornerBoxes(const Scene& scene, const Hit& h00, const Hit& h10, const Hit& h01, const Hit& h11,
                int boxes[4]) {
  int num_boxes = 0;
  bool all_surfaces = true;
  for (const Hit* corner : {&h00, &h10, &h01, &h11}) {
    all_surfaces = all_surfaces && corner->surface >= 0;
    const int box = scene.BoxOfSurface(corner->surface);
    if (box >= 0 && std::find(boxes, boxes + num_boxes, box) == boxes + num_boxes) {
      boxes[num_boxes++] = box;
    }
  }
  return all_surfaces ? num_boxes : -1;
}

// Renders block (bi, bj) of the grid (its pixels between node columns bi, bi + 1 and rows bj,
// bj + 1) from the node hits: interpolated when its corners see one surface, else cast pixel by
// pixel against the boxes its corners hit when every corner hits a surface (an object seen by no
// corner is missed, as in uniform blocks).
void RenderBlock(const Scene& scene, const PixelCaster& caster, const NodeGrid& grid,
                 const std::vector<Hit>& hits, int bi, int bj, float weight, float* acc,
                 RenderKernel kernel) {
  const int block = grid.block;
  const int gx = grid.nodes_x;
  const int x0 = bi * block;
  const int x1 = std::min(caster.width(), x0 + block);
  const int y0 = bj * block;
  const int y1 = std::min(caster.height(), y0 + block);
  const Hit& h00 = hits[static_cast<size_t>(bj) * gx + bi];
  const Hit& h10 = hits[static_cast<size_t>(bj) * gx + bi + 1];
  const Hit& h01 = hits[static_cast<size_t>(bj + 1) * gx + bi];
  const Hit& h11 = hits[static_cast<size_t>(bj + 1) * gx + bi + 1];
  if (!IsUniformBlock(scene, h00, h10, h01, h11)) {
    int boxes[4];
    const int num_boxes = CornerBoxes(scene, h00, h10, h01, h11, boxes);
    caster.AddRays(x0, x1, y0, y1, num_boxes >= 0 ? boxes : nullptr, num_boxes, weight, acc);
    return;
  }
  if (h00.surface == kInvalid) return;
  FillBlock(scene, h00, h10, h01, h11, block, x1 - x0, y1 - y0, weight,
            acc + static_cast<size_t>(y0) * caster.width() + x0, caster.width(), kernel);
}

}  // namespace

CameraTables MakeCameraTables(std::shared_ptr<const camera::CameraModel> model) {
  CameraTables tables;
  tables.width = model->width();
  tables.height = model->height();
  tables.bearings.resize(static_cast<size_t>(tables.width) * tables.height * 3);
  double min_axis_cos = 1.0;
  for (int y = 0; y < tables.height; ++y) {
    for (int x = 0; x < tables.width; ++x) {
      float* b = &tables.bearings[3 * (static_cast<size_t>(y) * tables.width + x)];
      const auto bearing = model->Unproject(Eigen::Vector2d(x, y));
      if (bearing && bearing->allFinite() && bearing->norm() > 0.5) {
        const Eigen::Vector3d unit = bearing->normalized();
        b[0] = static_cast<float>(unit.x());
        b[1] = static_cast<float>(unit.y());
        b[2] = static_cast<float>(unit.z());
        min_axis_cos = std::min(min_axis_cos, unit.z());
      } else {
        b[0] = b[1] = b[2] = kNaN;
      }
    }
  }
  tables.max_axis_angle = static_cast<float>(std::acos(std::clamp(min_axis_cos, -1.0, 1.0)));
  tables.model = std::move(model);
  return tables;
}

NodeGrid MakeNodeGrid(const CameraTables& camera, int block) {
  NodeGrid grid;
  grid.block = block;
  grid.nodes_x = (camera.width - 1 + block - 1) / block + 1;
  grid.nodes_y = (camera.height - 1 + block - 1) / block + 1;
  const size_t n = static_cast<size_t>(grid.nodes_x) * grid.nodes_y;
  grid.bearings.assign(3 * n, kNaN);
  grid.pixel_angle.assign(n, 0.f);
  auto bearing_at = [&](double x, double y) -> std::optional<Eigen::Vector3d> {
    const auto b = camera.model->Unproject(Eigen::Vector2d(x, y));
    if (!b || !b->allFinite() || b->norm() < 0.5) return std::nullopt;
    return b->normalized();
  };
  for (int j = 0; j < grid.nodes_y; ++j) {
    for (int i = 0; i < grid.nodes_x; ++i) {
      const double x = i * block;
      const double y = j * block;
      const auto b = bearing_at(x, y);
      if (!b) continue;
      const size_t k = static_cast<size_t>(j) * grid.nodes_x + i;
      grid.bearings[3 * k] = static_cast<float>(b->x());
      grid.bearings[3 * k + 1] = static_cast<float>(b->y());
      grid.bearings[3 * k + 2] = static_cast<float>(b->z());
      grid.max_axis_angle = std::max(grid.max_axis_angle,
                                     static_cast<float>(std::acos(std::clamp(b->z(), -1.0, 1.0))));
      // Local pixel angle: the larger of the angles to the next pixel right and down.
      double angle = 0.0;
      for (const Eigen::Vector2d& step : {Eigen::Vector2d(1, 0), Eigen::Vector2d(0, 1)}) {
        auto nb = bearing_at(x + step.x(), y + step.y());
        if (!nb) nb = bearing_at(x - step.x(), y - step.y());
        if (nb) angle = std::max(angle, std::acos(std::clamp(b->dot(*nb), -1.0, 1.0)));
      }
      grid.pixel_angle[k] = static_cast<float>(angle > 0 ? angle : 1e-3);
    }
  }
  return grid;
}

namespace {
// The largest angle from the optical axis of a ray the view casts (pixels and nodes), radians.
double MaxAxisAngle(const CameraTables& camera, const NodeGrid* grid) {
  const bool nodes = grid != nullptr && grid->block >= 2;
  return std::max(camera.max_axis_angle, nodes ? grid->max_axis_angle : 0.f) + 1e-3;  // rounding
}

// Renders the view of `camera` from the row transforms `xf` (RenderAccumulate).
void RenderWith(const Scene& scene, const CameraTables& camera, const NodeGrid* grid,
                const RowTransforms& xf, float weight, float* acc, std::vector<Hit>* hits,
                RenderKernel kernel) {
  const PixelCaster caster(scene, camera, xf);
  if (grid == nullptr || grid->block < 2) {
    caster.AddRays(0, camera.width, 0, camera.height, nullptr, 0, weight, acc);
    return;
  }
  CastNodes(scene, *grid, xf, hits);
  for (int bj = 0; bj + 1 < grid->nodes_y; ++bj) {
    for (int bi = 0; bi + 1 < grid->nodes_x; ++bi) {
      RenderBlock(scene, caster, *grid, *hits, bi, bj, weight, acc, kernel);
    }
  }
}
}  // namespace

void RenderAccumulate(const Scene& scene, const CameraTables& camera, const NodeGrid* grid,
                      const Pose& world_from_camera, float weight, float* acc,
                      std::vector<Hit>* hits, RenderKernel kernel, const float* moving) {
  if (scene.MovingBoxCount() == 0) moving = nullptr;
  RowTransforms xf(world_from_camera, moving, scene.MovingBoxCount());
  if (xf.has_moving()) xf.CullMoving(scene.MovingBoxRadius(), MaxAxisAngle(camera, grid));
  RenderWith(scene, camera, grid, xf, weight, acc, hits, kernel);
}

void RenderAccumulateRows(const Scene& scene, const CameraTables& camera, const NodeGrid* grid,
                          const RowPose& world_from_camera_at_row, float weight, float* acc,
                          std::vector<Hit>* hits, RenderKernel kernel,
                          const RowMoving& moving_at_row) {
  const bool nodes = grid != nullptr && grid->block >= 2;
  const int num_rows =
      nodes ? std::max(camera.height, (grid->nodes_y - 1) * grid->block + 1) : camera.height;
  RowTransforms xf(world_from_camera_at_row, moving_at_row, scene.MovingBoxCount(), num_rows);
  if (xf.has_moving()) xf.CullMoving(scene.MovingBoxRadius(), MaxAxisAngle(camera, grid));
  RenderWith(scene, camera, grid, xf, weight, acc, hits, kernel);
}

}  // namespace rigcal::sim::internal
