#include "sim/SyntheticRenderer.h"

#include "io/SourceFiles.h"

#include <visp3/core/vpImage.h>
#include <visp3/core/vpIoTools.h>
#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace hslam
{
namespace
{
// The room (metres, world frame x right, y down, z forward): 5 m wide, 2.6 m high, 5.5 m deep.
constexpr double kRoomLo[3] = {-2.5, -1.2, -2.0};
constexpr double kRoomHi[3] = {2.5, 1.4, 3.5};
// Boxes standing on the floor (y = 1.4) and a pillar, placed outside the camera's path, for parallax.
constexpr double kBoxLo[3][3] = {{-1.7, 0.7, 1.4}, {0.7, 0.8, 2.0}, {-0.25, -1.2, 2.7}};
constexpr double kBoxHi[3][3] = {{-1.0, 1.4, 2.1}, {1.5, 1.4, 2.8}, {0.25, 1.4, 3.1}};

// Photographs of visp-images-data used as textures, in the order faces ask for them.
const char *const kTexturePaths[] = {
    "Solvay/Solvay_conference_1927_Version2_2126x1463.png", // 0 front wall
    "Klimt/Klimt.png",                                      // 1 left wall, pillar
    "cube/image.0000.pgm",                                  // 2 ceiling (comic pages: rich texture)
    "mbt-depth/Castle-simu/Images/Image_0001.pgm",          // 3 back wall (rarely seen)
    "AprilTag/AprilTag.pgm",                                // 4 floor
    "calibration/grid36-01.pgm",                            // 5 box 0
    "mire-2/image.0001.pgm",                                // 6 right wall
    "mire/mire.pgm"                                         // 7 box 1
};
constexpr int kTextureCount = sizeof(kTexturePaths) / sizeof(kTexturePaths[0]);

// Texture (index into kTexturePaths) and albedo of room faces, in the order 2 * axis + isHigh:
// x low (left), x high (right), y low (ceiling), y high (floor), z low (back), z high (front).
constexpr int kRoomTexture[6] = {1, 6, 2, 4, 3, 0};
constexpr float kRoomAlbedo[6] = {0.95f, 0.9f, 0.8f, 0.85f, 0.9f, 1.0f};
constexpr int kBoxTexture[3] = {5, 7, 1};
constexpr float kBoxAlbedo[3] = {0.9f, 1.0f, 0.85f};

// Finest texel allowed on a surface: 5 mm. A photograph smaller than its face is mirror-tiled rather than
// stretched, so surfaces keep gradients when the camera comes close.
constexpr double kMinTexelsPerMetre = 200.0;
// Mip pyramid stops when a level gets this small (pixels).
constexpr int kMinMipSize = 8;
// Grazing rays: the cosine used for the footprint is bounded to keep the mip level finite.
constexpr double kMinCosine = 0.05;
constexpr double kRayEpsilon = 1e-12;
// A picture's centre must be this close to a wall (metres); one texel of a picture is at most this wide.
constexpr double kPictureOnWallMetres = 1e-3;
constexpr double kPictureTexelMetres = 2.5e-3;

inline int mirrorIndex(int i, int n)
{
  if (static_cast<unsigned int>(i) < static_cast<unsigned int>(n)) {
    return i; // the common case: no tiling
  }
  const int period = 2 * n;
  int m = i % period;
  if (m < 0) {
    m += period;
  }
  return m < n ? m : period - 1 - m;
}
} // namespace

void SyntheticRenderer::load(const std::string &imagesDir)
{
  m_textures.clear();
  m_textureFiles.clear();
  std::vector<int> loadedIndex(kTextureCount, -1);
  for (int i = 0; i < kTextureCount; ++i) {
    const std::string path = imagesDir + "/" + kTexturePaths[i];
    if (!vpIoTools::checkFilename(path)) {
      continue;
    }
    vpImage<unsigned char> I;
    try {
      io::readGreyImage(path, I);
    } catch (const vpHSlamException &) {
      continue; // an unreadable photograph is replaced like a missing one
    }
    MipLevel L0;
    L0.width = static_cast<int>(I.getWidth());
    L0.height = static_cast<int>(I.getHeight());
    L0.scale = 1.0;
    L0.pixels.assign(I.bitmap, I.bitmap + I.getSize());
    Texture T = makeTexture(std::move(L0));
    loadedIndex[i] = static_cast<int>(m_textures.size());
    m_textures.push_back(std::move(T));
    m_textureFiles.push_back(path);
  }
  if (m_textures.empty()) {
    throw vpHSlamException(vpHSlamException::fileNotFound,
                           "synthetic scene: no texture photograph found under '" + imagesDir + "' (looked for " +
                               kTexturePaths[0] +
                               " and others; install the Debian package visp-images-data or set "
                               "VISP_INPUT_IMAGE_PATH)");
  }
  // Missing photographs: take the found ones in turn.
  int next = 0;
  for (int i = 0; i < kTextureCount; ++i) {
    if (loadedIndex[i] < 0) {
      loadedIndex[i] = next;
      next = (next + 1) % static_cast<int>(m_textures.size());
    }
  }

  std::copy(kRoomLo, kRoomLo + 3, m_roomLo);
  std::copy(kRoomHi, kRoomHi + 3, m_roomHi);
  m_faces.clear();
  m_boxes.clear();
  for (int a = 0; a < 3; ++a) {
    for (int side = 0; side < 2; ++side) {
      addFace(a, m_roomLo, m_roomHi, loadedIndex[kRoomTexture[2 * a + side]], kRoomAlbedo[2 * a + side]);
    }
  }
  for (int b = 0; b < 3; ++b) {
    Box B;
    std::copy(kBoxLo[b], kBoxLo[b] + 3, B.lo);
    std::copy(kBoxHi[b], kBoxHi[b] + 3, B.hi);
    m_boxes.push_back(B);
    for (int a = 0; a < 3; ++a) {
      for (int side = 0; side < 2; ++side) {
        addFace(a, B.lo, B.hi, loadedIndex[kBoxTexture[b]], kBoxAlbedo[b]);
      }
    }
  }
}

SyntheticRenderer::Texture SyntheticRenderer::makeTexture(MipLevel level0)
{
  Texture T;
  T.levels.push_back(std::move(level0));
  // Box-filtered pyramid (2x2 mean, clamped at odd borders).
  while (std::min(T.levels.back().width, T.levels.back().height) / 2 >= kMinMipSize) {
    const MipLevel &P = T.levels.back();
    MipLevel N;
    N.width = P.width / 2;
    N.height = P.height / 2;
    N.scale = 0.5 * P.scale;
    N.pixels.resize(static_cast<size_t>(N.width) * N.height);
    for (int y = 0; y < N.height; ++y) {
      const int y0 = 2 * y, y1 = std::min(2 * y + 1, P.height - 1);
      for (int x = 0; x < N.width; ++x) {
        const int x0 = 2 * x, x1 = std::min(2 * x + 1, P.width - 1);
        N.pixels[static_cast<size_t>(y) * N.width + x] =
            0.25f *
            (P.pixels[static_cast<size_t>(y0) * P.width + x0] + P.pixels[static_cast<size_t>(y0) * P.width + x1] +
             P.pixels[static_cast<size_t>(y1) * P.width + x0] + P.pixels[static_cast<size_t>(y1) * P.width + x1]);
      }
    }
    T.levels.push_back(std::move(N));
  }
  return T;
}

void SyntheticRenderer::pictureAxes(const double centre[3], double xAxis[3], double yAxis[3], double zAxis[3])
{
  // The wall: x or z at a bound of the room. Its inward-facing picture has y down (the world's y) and z along the
  // wall's outward normal, so x = y x z reads left to right for a viewer inside the room.
  int axis = -1;
  double normal = 0.;
  for (int a : {0, 2}) {
    if (std::fabs(centre[a] - kRoomLo[a]) <= kPictureOnWallMetres) {
      axis = a;
      normal = -1.;
    } else if (std::fabs(centre[a] - kRoomHi[a]) <= kPictureOnWallMetres) {
      axis = a;
      normal = 1.;
    }
  }
  if (axis < 0 || !std::isfinite(centre[1])) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "synthetic scene: a picture's centre must lie on one of the four walls (x = -2.5 or 2.5, "
                           "or z = -2 or 3.5, metres)");
  }
  for (int k = 0; k < 3; ++k) {
    zAxis[k] = (k == axis) ? normal : 0.;
    yAxis[k] = (k == 1) ? 1. : 0.;
  }
  // x = y cross z with y = (0, 1, 0): (z_z, 0, -z_x).
  xAxis[0] = zAxis[2];
  xAxis[1] = 0.;
  xAxis[2] = -zAxis[0];
}

void SyntheticRenderer::setPictures(const std::vector<SimPicture> &pictures)
{
  std::vector<Picture> made;
  for (const SimPicture &in : pictures) {
    if (in.width <= 0 || in.height <= 0 || in.pixels.size() != static_cast<size_t>(in.width) * in.height ||
        !(in.widthMetres > 0.)) {
      throw vpHSlamException(vpHSlamException::invalidArgument,
                             "synthetic scene: a picture needs pixels and a positive width in metres");
    }
    Picture P;
    double zAxis[3];
    pictureAxes(in.centre, P.xAxis, P.yAxis, zAxis);
    std::copy(in.centre, in.centre + 3, P.centre);
    P.face = 0;
    for (int a = 0; a < 3; ++a) {
      if (zAxis[a] != 0.) {
        P.face = 2 * a + (zAxis[a] > 0. ? 1 : 0);
      }
    }
    P.halfWidth = 0.5 * in.widthMetres;
    P.halfHeight = P.halfWidth * in.height / in.width;
    for (int a = 0; a < 3; ++a) {
      const double half = std::fabs(P.xAxis[a]) * P.halfWidth + std::fabs(P.yAxis[a]) * P.halfHeight;
      if (P.centre[a] - half < kRoomLo[a] - kPictureOnWallMetres ||
          P.centre[a] + half > kRoomHi[a] + kPictureOnWallMetres) {
        throw vpHSlamException(vpHSlamException::invalidArgument,
                               "synthetic scene: a picture does not fit on its wall");
      }
    }
    // Magnified by whole texels (nearest), so printed edges stay sharp up close; the mip levels blur them only
    // as far away as the camera's pixel footprint asks.
    const int magnify = std::max(1, static_cast<int>(std::ceil(in.widthMetres / kPictureTexelMetres / in.width)));
    MipLevel L0;
    L0.width = in.width * magnify;
    L0.height = in.height * magnify;
    L0.scale = 1.0;
    L0.pixels.resize(static_cast<size_t>(L0.width) * L0.height);
    for (int y = 0; y < L0.height; ++y) {
      for (int x = 0; x < L0.width; ++x) {
        L0.pixels[static_cast<size_t>(y) * L0.width + x] =
            in.pixels[static_cast<size_t>(y / magnify) * in.width + x / magnify];
      }
    }
    P.texelsPerMetre = L0.width / in.widthMetres;
    P.texture = makeTexture(std::move(L0));
    made.push_back(std::move(P));
  }
  m_pictures = std::move(made);
}

const SyntheticRenderer::Picture *SyntheticRenderer::pictureAt(int face, const double p[3], double &a, double &b) const
{
  for (const Picture &P : m_pictures) {
    if (P.face != face) {
      continue;
    }
    a = 0.;
    b = 0.;
    for (int k = 0; k < 3; ++k) {
      a += (p[k] - P.centre[k]) * P.xAxis[k];
      b += (p[k] - P.centre[k]) * P.yAxis[k];
    }
    if (std::fabs(a) < P.halfWidth && std::fabs(b) < P.halfHeight) {
      return &P;
    }
  }
  return nullptr;
}

void SyntheticRenderer::addFace(int normalAxis, const double lo[3], const double hi[3], int texture, float albedo)
{
  Face F;
  F.normalAxis = normalAxis;
  // Texture axes: walls x = const show (z, y), floor and ceiling show (x, z), walls z = const show (x, y).
  F.uAxis = normalAxis == 0 ? 2 : 0;
  F.vAxis = normalAxis == 1 ? 2 : 1;
  F.centreU = 0.5 * (lo[F.uAxis] + hi[F.uAxis]);
  F.centreV = 0.5 * (lo[F.vAxis] + hi[F.vAxis]);
  const MipLevel &L0 = m_textures[static_cast<size_t>(texture)].levels.front();
  // The whole face inside the photograph (cropped along one side), unless that makes texels too coarse.
  const double fit = std::min(L0.width / (hi[F.uAxis] - lo[F.uAxis]), L0.height / (hi[F.vAxis] - lo[F.vAxis]));
  F.texelsPerMetre = std::max(kMinTexelsPerMetre, fit);
  F.texture = texture;
  F.albedo = albedo;
  m_faces.push_back(F);
}

int SyntheticRenderer::castRay(const double o[3], const double d[3], double &t) const
{
  // Inside the closed room each ray leaves through exactly one wall per axis: the nearest of these three.
  int face = -1;
  t = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (d[a] > kRayEpsilon) {
      const double ta = (m_roomHi[a] - o[a]) / d[a];
      if (ta < t) {
        t = ta;
        face = 2 * a + 1;
      }
    } else if (d[a] < -kRayEpsilon) {
      const double ta = (m_roomLo[a] - o[a]) / d[a];
      if (ta < t) {
        t = ta;
        face = 2 * a;
      }
    }
  }
  // Boxes: slab test (Kay and Kajiya), entry face = the axis whose slab is entered last.
  for (size_t b = 0; b < m_boxes.size(); ++b) {
    const Box &B = m_boxes[b];
    double tEnter = -std::numeric_limits<double>::infinity(), tExit = std::numeric_limits<double>::infinity();
    int enterFace = -1;
    bool miss = false;
    for (int a = 0; a < 3 && !miss; ++a) {
      if (std::fabs(d[a]) <= kRayEpsilon) {
        miss = o[a] < B.lo[a] || o[a] > B.hi[a];
        continue;
      }
      const double inv = 1.0 / d[a];
      double t0 = (B.lo[a] - o[a]) * inv, t1 = (B.hi[a] - o[a]) * inv;
      int side = 0; // entering through the low face when moving towards +a
      if (t0 > t1) {
        std::swap(t0, t1);
        side = 1;
      }
      if (t0 > tEnter) {
        tEnter = t0;
        enterFace = 2 * a + side;
      }
      tExit = std::min(tExit, t1);
    }
    if (!miss && enterFace >= 0 && tEnter <= tExit && tEnter > 0.0 && tEnter < t) {
      t = tEnter;
      face = 6 + 6 * static_cast<int>(b) + enterFace;
    }
  }
  return face;
}

float SyntheticRenderer::sample(const Texture &T, double tu, double tv, double level) const
{
  const int maxLevel = static_cast<int>(T.levels.size()) - 1;
  level = std::min(level, static_cast<double>(maxLevel));
  const int l0 = static_cast<int>(level);
  const int l1 = std::min(l0 + 1, maxLevel);
  const float w1 = static_cast<float>(level - l0);
  float value[2] = {0.f, 0.f};
  const int levels[2] = {l0, l1};
  // One level suffices when the blend weight is zero (magnification, or the coarsest level).
  const int count = (l1 == l0 || w1 == 0.f) ? 1 : 2;
  for (int k = 0; k < count; ++k) {
    const MipLevel &L = T.levels[static_cast<size_t>(levels[k])];
    const double scale = L.scale;
    // Texel centres at integer coordinates on every level.
    const double x = (tu + 0.5) * scale - 0.5, y = (tv + 0.5) * scale - 0.5;
    const double fx = std::floor(x), fy = std::floor(y);
    const float ax = static_cast<float>(x - fx), ay = static_cast<float>(y - fy);
    const int x0 = mirrorIndex(static_cast<int>(fx), L.width), x1 = mirrorIndex(static_cast<int>(fx) + 1, L.width);
    const int y0 = mirrorIndex(static_cast<int>(fy), L.height), y1 = mirrorIndex(static_cast<int>(fy) + 1, L.height);
    const float *r0 = &L.pixels[static_cast<size_t>(y0) * L.width];
    const float *r1 = &L.pixels[static_cast<size_t>(y1) * L.width];
    value[k] = (1.f - ay) * ((1.f - ax) * r0[x0] + ax * r0[x1]) + ay * ((1.f - ax) * r1[x0] + ax * r1[x1]);
  }
  return (1.f - w1) * value[0] + w1 * value[1];
}

float SyntheticRenderer::shade(const double o[3], const double d[3], double pixelAngle) const
{
  double t;
  const int faceIndex = castRay(o, d, t);
  if (faceIndex < 0) {
    return 0.f;
  }
  const Face &F = m_faces[static_cast<size_t>(faceIndex)];
  const double p[3] = {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
  const double norm = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  const double cosine = std::max(kMinCosine, std::fabs(d[F.normalAxis]) / norm);
  // Footprint of one sample on the surface (metres): distance x angle, stretched by 1/cos along the slant;
  // the geometric mean of both directions picks an isotropic mip level.
  const double footprint = t * norm * pixelAngle / std::sqrt(cosine);
  if (faceIndex < 6 && !m_pictures.empty()) {
    double a = 0., b = 0.;
    if (const Picture *picture = pictureAt(faceIndex, p, a, b)) {
      const double texels = footprint * picture->texelsPerMetre;
      const MipLevel &P0 = picture->texture.levels.front();
      return sample(picture->texture, a * picture->texelsPerMetre + 0.5 * P0.width - 0.5,
                    b * picture->texelsPerMetre + 0.5 * P0.height - 0.5, texels > 1.0 ? std::log2(texels) : 0.0);
    }
  }
  const double texels = footprint * F.texelsPerMetre;
  const double level = texels > 1.0 ? std::log2(texels) : 0.0;
  const Texture &T = m_textures[static_cast<size_t>(F.texture)];
  const MipLevel &L0 = T.levels.front();
  const double tu = (p[F.uAxis] - F.centreU) * F.texelsPerMetre + 0.5 * L0.width;
  const double tv = (p[F.vAxis] - F.centreV) * F.texelsPerMetre + 0.5 * L0.height;
  return F.albedo * sample(T, tu, tv, level);
}

void SyntheticRenderer::render(const SimPose &P, const SimIntrinsics &K, unsigned int ss, float *irradiance) const
{
  const double *R = P.wRc;
  const double pixelAngle = 2.0 / ((K.fx + K.fy) * ss);
  const float weight = 1.f / static_cast<float>(ss * ss);
  // Rows are independent: parallel rows give the same numbers as a sequential run.
#pragma omp parallel for schedule(static)
  for (unsigned int v = 0; v < K.height; ++v) {
    for (unsigned int u = 0; u < K.width; ++u) {
      float sum = 0.f;
      for (unsigned int sy = 0; sy < ss; ++sy) {
        const double y = ((v + (sy + 0.5) / ss - 0.5) - K.cy) / K.fy;
        for (unsigned int sx = 0; sx < ss; ++sx) {
          const double x = ((u + (sx + 0.5) / ss - 0.5) - K.cx) / K.fx;
          // Ray in the world frame with camera z = 1, so the hit parameter is the depth.
          const double d[3] = {R[0] * x + R[1] * y + R[2], R[3] * x + R[4] * y + R[5], R[6] * x + R[7] * y + R[8]};
          sum += shade(P.wtc, d, pixelAngle);
        }
      }
      irradiance[static_cast<size_t>(v) * K.width + u] = sum * weight;
    }
  }
}

bool SyntheticRenderer::worldPoint(const SimPose &P, const SimIntrinsics &K, double u, double v, double Pw[3],
                                   double &depth) const
{
  const double *R = P.wRc;
  const double x = (u - K.cx) / K.fx, y = (v - K.cy) / K.fy;
  const double d[3] = {R[0] * x + R[1] * y + R[2], R[3] * x + R[4] * y + R[5], R[6] * x + R[7] * y + R[8]};
  double t;
  if (castRay(P.wtc, d, t) < 0) {
    return false;
  }
  for (int a = 0; a < 3; ++a) {
    Pw[a] = P.wtc[a] + t * d[a];
  }
  depth = t;
  return true;
}
} // namespace hslam
