// Rendering of the simulated rig: bearing tables, node grids, and a view rendered by ray casting
// at the nodes and filling texture blocks between them.
#include "sim_render.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "sim_texture_sampling.h"

namespace rigcal::sim::internal {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

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

}  // namespace

CameraTables MakeCameraTables(std::shared_ptr<const camera::CameraModel> model) {
  CameraTables tables;
  tables.width = model->width();
  tables.height = model->height();
  tables.bearings.resize(static_cast<size_t>(tables.width) * tables.height * 3);
  for (int y = 0; y < tables.height; ++y) {
    for (int x = 0; x < tables.width; ++x) {
      float* b = &tables.bearings[3 * (static_cast<size_t>(y) * tables.width + x)];
      const auto bearing = model->Unproject(Eigen::Vector2d(x, y));
      if (bearing && bearing->allFinite() && bearing->norm() > 0.5) {
        const Eigen::Vector3d unit = bearing->normalized();
        b[0] = static_cast<float>(unit.x());
        b[1] = static_cast<float>(unit.y());
        b[2] = static_cast<float>(unit.z());
      } else {
        b[0] = b[1] = b[2] = kNaN;
      }
    }
  }
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

void RenderAccumulate(const Scene& scene, const CameraTables& camera, const NodeGrid* grid,
                      const Pose& world_from_camera, float weight, float* acc,
                      std::vector<Hit>* hits, RenderKernel kernel) {
  Transform xf;
  const Eigen::Matrix3d r = world_from_camera.R();
  for (int i = 0; i < 9; ++i) xf.r[i] = static_cast<float>(r(i / 3, i % 3));
  for (int i = 0; i < 3; ++i) xf.o[i] = static_cast<float>(world_from_camera.C[i]);
  const int w = camera.width;
  const int h = camera.height;

  auto shade = [&scene](const Hit& hit) -> float {
    if (hit.surface == kInvalid) return 0.f;
    if (hit.surface == kSky) return hit.u;
    return SampleTrilinear(scene.Texture(hit.surface), hit.u, hit.v, hit.lod);
  };
  // Boxes a fallback block may show: those its corners hit (null: unknown, test all).
  const int* candidates = nullptr;
  int num_candidates = 0;
  auto cast_pixel = [&](int x, int y) -> float {
    const float* b = &camera.bearings[3 * (static_cast<size_t>(y) * w + x)];
    if (b[0] != b[0]) return 0.f;
    // Local pixel angle as for the nodes: the larger of the chords to the next pixel right and
    // down (the previous one at the last column / row).
    float pixel_angle = 0.f;
    for (const float* nb : {x + 1 < w ? b + 3 : b - 3, y + 1 < h ? b + 3 * w : b - 3 * w}) {
      if (nb[0] != nb[0]) continue;
      const float dx = nb[0] - b[0], dy = nb[1] - b[1], dz = nb[2] - b[2];
      pixel_angle = std::max(pixel_angle, std::sqrt(dx * dx + dy * dy + dz * dz));
    }
    if (pixel_angle <= 0.f) pixel_angle = 1e-3f;
    float d[3];
    xf.Apply(b, d);
    return shade(candidates != nullptr
                     ? scene.CastAmong(xf.o, d, pixel_angle, candidates, num_candidates)
                     : scene.Cast(xf.o, d, pixel_angle));
  };

  if (grid == nullptr || grid->block < 2) {
    for (int y = 0; y < h; ++y) {
      float* row = acc + static_cast<size_t>(y) * w;
      for (int x = 0; x < w; ++x) row[x] += weight * cast_pixel(x, y);
    }
    return;
  }

  const int block = grid->block;
  const int gx = grid->nodes_x;
  const int gy = grid->nodes_y;
  hits->resize(static_cast<size_t>(gx) * gy);
  for (size_t k = 0; k < hits->size(); ++k) {
    const float* b = &grid->bearings[3 * k];
    if (b[0] != b[0]) {
      (*hits)[k].surface = kInvalid;
      continue;
    }
    float d[3];
    xf.Apply(b, d);
    (*hits)[k] = scene.Cast(xf.o, d, grid->pixel_angle[k]);
  }

  for (int bj = 0; bj + 1 < gy; ++bj) {
    const int y0 = bj * block;
    const int y1 = std::min(h, y0 + block);
    for (int bi = 0; bi + 1 < gx; ++bi) {
      const int x0 = bi * block;
      const int x1 = std::min(w, x0 + block);
      const Hit& h00 = (*hits)[static_cast<size_t>(bj) * gx + bi];
      const Hit& h10 = (*hits)[static_cast<size_t>(bj) * gx + bi + 1];
      const Hit& h01 = (*hits)[static_cast<size_t>(bj + 1) * gx + bi];
      const Hit& h11 = (*hits)[static_cast<size_t>(bj + 1) * gx + bi + 1];
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
      if (!uniform) {
        // Cast every pixel, against the boxes the corners hit when every corner hits a
        // surface (an object seen by no corner is missed, as in uniform blocks).
        int boxes[4];
        num_candidates = 0;
        bool all_surfaces = true;
        for (const Hit* corner : {&h00, &h10, &h01, &h11}) {
          all_surfaces = all_surfaces && corner->surface >= 0;
          const int box = scene.BoxOfSurface(corner->surface);
          if (box >= 0 && std::find(boxes, boxes + num_candidates, box) == boxes + num_candidates) {
            boxes[num_candidates++] = box;
          }
        }
        candidates = all_surfaces ? boxes : nullptr;
        for (int y = y0; y < y1; ++y) {
          float* row = acc + static_cast<size_t>(y) * w;
          for (int x = x0; x < x1; ++x) row[x] += weight * cast_pixel(x, y);
        }
        candidates = nullptr;
        continue;
      }
      if (s == kInvalid) continue;
      FillBlock(scene, h00, h10, h01, h11, block, x1 - x0, y1 - y0, weight,
                acc + static_cast<size_t>(y0) * w + x0, w, kernel);
    }
  }
}

}  // namespace rigcal::sim::internal
