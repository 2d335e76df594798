/*
 * H-SLAM for ViSP.
 */
/*!
  \file vpHSlamRectifier.h
  \brief Rectification of input images to the ideal pinhole camera the system works with.
*/
#ifndef VP_HSLAM_RECTIFIER_H
#define VP_HSLAM_RECTIFIER_H

#include <visp3/core/vpCameraParameters.h>
#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImage.h>
#include <visp3/core/vpImagePoint.h>
#include <visp3/hslam/vpHSlamCamera.h>

#include <memory>

/*!
  \class vpHSlamRectifier
  \ingroup group_hslam
  \brief Turns images of a calibrated camera (pinhole, radial-tangential, equidistant or FOV) into images of an
  ideal pinhole camera, through a remap table computed once.

  What it is for: tracking and mapping assume a distortion-free pinhole camera. The constructor chooses that
  target camera from the calibration's rectification mode (vpHSlamCamera::RectificationMode):
  - crop: the largest pinhole image whose every pixel sees the input image (DSO's optimal crop: the lines through
    the optical axis are stretched to the image border, then the rectangle's sides are shrunk until every border
    ray lands in the input image); fx and fy may differ, as in DSO;
  - full: the smallest pinhole image that still contains every input pixel (black, i.e. 0, where no input pixel
    maps); impossible, and refused, when the input sees 90 degrees or more from the optical axis;
  - explicit: the intrinsics given to vpHSlamCamera::setRectification();
  - none: the input intrinsics. For a pinhole input this is a plain copy (isPassThrough()).
  It then precomputes, per target pixel, where to read the input (top-left neighbour index and fixed-point
  bilinear fractions, 1/2048 px). rectify() only applies that table: no allocation once the output has the
  target size, no branch and no virtual call per pixel (about 1 ms per 640x480 frame on one core).

  Pixels: (0,0) is the centre of the top-left pixel, in the input and in the target. Target pixels without a
  source pixel (possible with full or explicit targets) are set to 0; getInvalidPixelCount() and getValidMask()
  say which.

  Threading and ownership: a value type that owns its table. Construction is the costly part (one projection per
  target pixel plus the crop search, a few tens of ms); rectify(), rectifyPoint() and distortPoint() are const and
  may run concurrently on different outputs. A moved-from rectifier may only be assigned to or destroyed.

  \code
  vpHSlamCamera cam(vpHSlamCamera::radialTangential, 752, 480, 458.654, 457.296, 367.215, 248.375,
                    {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05}); // rectifyCrop by default
  vpHSlamRectifier rectifier(cam);
  vpCameraParameters K = rectifier.getCameraParameters(); // the pinhole camera of the rectified images
  vpImage<unsigned char> I, Irect;
  // ... acquire I (752x480) ...
  rectifier.rectify(I, Irect); // Irect is getWidth() x getHeight()
  \endcode
*/
class VISP_EXPORT vpHSlamRectifier
{
public:
  /*!
    Compute the target camera and the remap table.
    \param camera : input calibration and rectification mode.
    \exception vpHSlamException::unsupported when the target cannot be built (full rectification of a lens
    seeing 90 degrees or more, crop of an image whose principal point is outside it).
  */
  explicit vpHSlamRectifier(const vpHSlamCamera &camera);
  vpHSlamRectifier(const vpHSlamRectifier &other);                //!< copies the remap tables
  vpHSlamRectifier(vpHSlamRectifier &&other) noexcept;            //!< takes the remap tables
  vpHSlamRectifier &operator=(const vpHSlamRectifier &other);     //!< copies the remap tables
  vpHSlamRectifier &operator=(vpHSlamRectifier &&other) noexcept; //!< takes the remap tables
  ~vpHSlamRectifier();

  /*!
    Rectify an 8-bit image (bilinear interpolation, rounded).
    \param I : input image, of the calibration's size.
    \param Irect : rectified image; resized to getHeight() x getWidth() only if its size differs.
    \exception vpHSlamException::invalidImage when I does not have the calibration's size (both sizes are named);
    invalidArgument when I and Irect are the same object (except for a pass-through rectifier, where it is a no-op).
  */
  void rectify(const vpImage<unsigned char> &I, vpImage<unsigned char> &Irect) const;
  //! Rectify a float image (bilinear interpolation); same contract as the 8-bit version.
  void rectify(const vpImage<float> &I, vpImage<float> &Irect) const;

  //! Target (rectified) pinhole camera, vpCameraParameters::perspectiveProjWithoutDistortion.
  vpCameraParameters getCameraParameters() const;
  unsigned int getWidth() const;  //!< target width, pixels
  unsigned int getHeight() const; //!< target height, pixels
  //! The input calibration this rectifier was built from.
  const vpHSlamCamera &getCamera() const;
  //! True when rectify() is a plain copy (pinhole input, target equal to the input).
  bool isPassThrough() const;
  //! Number of target pixels with no input pixel (set to 0 by rectify()); 0 for crop.
  unsigned int getInvalidPixelCount() const;
  //! Validity of each target pixel (true: it has an input pixel).
  void getValidMask(vpImage<bool> &mask) const;

  /*!
    Map an input (distorted) pixel to the rectified image.
    \return false when the pixel has no rectified position (outside the model's domain, or a ray at or beyond
    90 degrees). A true result may lie outside the rectified image.
  */
  bool rectifyPoint(const vpImagePoint &ipInput, vpImagePoint &ipRect) const;
  /*!
    Map a rectified pixel to the input (distorted) image.
    \return false when the ray is outside the model's domain. A true result may lie outside the input image.
  */
  bool distortPoint(const vpImagePoint &ipRect, vpImagePoint &ipInput) const;

private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

#endif
