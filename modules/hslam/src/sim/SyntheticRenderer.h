// Ray-casting renderer of the synthetic room: textured planes, mip-mapped bilinear look-up, supersampling.
#ifndef HSLAM_SIM_SYNTHETIC_RENDERER_H
#define HSLAM_SIM_SYNTHETIC_RENDERER_H

#include "sim/SyntheticTrajectory.h"

#include <string>
#include <vector>

namespace hslam
{
//! Pinhole intrinsics of the rendered images (pixels, (0,0) = centre of the top-left pixel).
struct SimIntrinsics {
  double fx, fy, cx, cy;
  unsigned int width, height;
};

/*!
  The scene: a closed room (six axis-aligned walls) with three boxes inside for parallax, every face textured with
  a real photograph from ViSP's image data (Debian package visp-images-data). World frame: x right, y down (towards
  the floor), z forward, metres.

  Rendering casts one ray per sub-pixel sample from the camera centre, keeps the nearest face hit and reads the
  face's texture with trilinear mip-mapping (the mip level follows the sample's footprint on the surface, so far
  and grazing surfaces do not alias), then averages the samples of each pixel. The result is scene irradiance in
  grey levels [0, 255]; photometric effects are applied by the caller.

  Threading: immutable after load(); render() and worldPoint() are const and may run concurrently.
*/
class SyntheticRenderer
{
public:
  /*!
    Load the textures from ViSP's image folder (the "ViSP-images" directory). Missing photographs are replaced by
    the ones found.
    \exception vpHSlamException::fileNotFound naming the folder when none of the photographs is there.
  */
  void load(const std::string &imagesDir);

  //! Irradiance image (width x height floats, row-major) seen from pose P, ss x ss samples per pixel.
  void render(const SimPose &P, const SimIntrinsics &K, unsigned int ss, float *irradiance) const;

  /*!
    World point (metres) seen through pixel (u, v) from pose P; also its depth along the camera's z axis.
    \return false if the ray hits nothing (cannot happen inside the closed room, kept for safety).
  */
  bool worldPoint(const SimPose &P, const SimIntrinsics &K, double u, double v, double Pw[3], double &depth) const;

  //! Paths of the photographs actually used (for reports).
  const std::vector<std::string> &getTextureFiles() const { return m_textureFiles; }

private:
  struct MipLevel {
    std::vector<float> pixels;
    int width, height;
    double scale; //!< 2^-level: level-0 texel coordinates to this level's
  };
  struct Texture {
    std::vector<MipLevel> levels;
  };
  struct Face {
    int normalAxis, uAxis, vAxis;
    double centreU, centreV; //!< face centre along u and v (metres)
    double texelsPerMetre;
    int texture;
    float albedo;
  };
  struct Box {
    double lo[3], hi[3];
  };

  //! Nearest hit along o + t d (t > 0, d with camera z = 1 so t is the depth): face index and t.
  int castRay(const double o[3], const double d[3], double &t) const;
  //! Trilinear look-up; tu, tv in level-0 texels, level >= 0.
  float sample(const Texture &T, double tu, double tv, double level) const;
  //! Shade one ray: nearest face, texture look-up with a footprint of pixelAngle radians.
  float shade(const double o[3], const double d[3], double pixelAngle) const;
  void addFace(int normalAxis, const double lo[3], const double hi[3], int texture, float albedo);

  double m_roomLo[3], m_roomHi[3];
  std::vector<Box> m_boxes;
  std::vector<Face> m_faces; //!< 6 room faces (2 * axis + isHigh), then 6 per box
  std::vector<Texture> m_textures;
  std::vector<std::string> m_textureFiles;
};
} // namespace hslam

#endif
