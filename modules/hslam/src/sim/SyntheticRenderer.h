// Ray-casting renderer of the synthetic room: textured planes, mip-mapped bilinear look-up, supersampling.
#ifndef HSLAM_SIM_SYNTHETIC_RENDERER_H
#define HSLAM_SIM_SYNTHETIC_RENDERER_H

#include "sim/SyntheticTrajectory.h"

#include <string>
#include <vector>

namespace hslam
{
/*!
  A picture hung flat on one of the room's four walls (an AprilTag, a poster): its texels replace the wall's inside
  a rectangle, the geometry is the wall's. Frame of the picture: origin at its centre, x along its columns, y along
  its rows (down, as the world's y), z into the wall, so it reads as printed from inside the room.
*/
struct SimPicture {
  std::vector<unsigned char> pixels; //!< grey, row-major
  int width = 0, height = 0;         //!< pixels
  double centre[3] = {0., 0., 0.};   //!< world, metres, on the wall
  double widthMetres = 0.;           //!< printed width; the height follows the aspect ratio
};

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

  /*!
    Hang pictures on the walls (replaces the previous ones).
    \exception vpHSlamException::invalidArgument when a picture is empty, not positive in size, or its centre is not
    on one of the four walls (x or z at the room's bounds, within 1 mm) or it does not fit on that wall.
  */
  void setPictures(const std::vector<SimPicture> &pictures);
  /*!
    The frame of a picture hung at \e centre (world, metres): rotation columns x, y, z of SimPicture's frame.
    \exception vpHSlamException::invalidArgument when \e centre is not on one of the four walls.
  */
  static void pictureAxes(const double centre[3], double xAxis[3], double yAxis[3], double zAxis[3]);

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
  struct Picture {
    int face;                     //!< room face it hangs on
    double centre[3];             //!< world, metres
    double xAxis[3], yAxis[3];    //!< its columns and rows in the world
    double halfWidth, halfHeight; //!< metres
    double texelsPerMetre;
    Texture texture; //!< the picture magnified (nearest texel) so that one texel is at most kPictureTexelMetres
  };

  //! Nearest hit along o + t d (t > 0, d with camera z = 1 so t is the depth): face index and t.
  int castRay(const double o[3], const double d[3], double &t) const;
  //! Trilinear look-up; tu, tv in level-0 texels, level >= 0.
  float sample(const Texture &T, double tu, double tv, double level) const;
  //! Mip-mapped pyramid of a level-0 image (2x2 box filter).
  static Texture makeTexture(MipLevel level0);
  //! The picture hung on room face \e face that contains the world point \e p, or null; \e a, \e b: the point
  //! along the picture's columns and rows from its centre, metres.
  const Picture *pictureAt(int face, const double p[3], double &a, double &b) const;
  //! Shade one ray: nearest face, texture look-up with a footprint of pixelAngle radians.
  float shade(const double o[3], const double d[3], double pixelAngle) const;
  void addFace(int normalAxis, const double lo[3], const double hi[3], int texture, float albedo);

  double m_roomLo[3], m_roomHi[3];
  std::vector<Box> m_boxes;
  std::vector<Face> m_faces; //!< 6 room faces (2 * axis + isHigh), then 6 per box
  std::vector<Texture> m_textures;
  std::vector<std::string> m_textureFiles;
  std::vector<Picture> m_pictures;
};
} // namespace hslam

#endif
