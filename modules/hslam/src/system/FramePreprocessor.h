/*
 * H-SLAM for ViSP.
 */
/*!
  \file FramePreprocessor.h
  \brief From a raw camera image to a Frame: size check, rectification, photometric correction, image pyramid.

  Order of operations (ARCHITECTURE.md, "Input"): the photometric correction G(I)/V is applied in the INPUT
  geometry (the vignette lives there), then the float image is rectified; the 8-bit image is rectified separately
  and kept photometrically raw for feature detection. Without calibration the rectified 8-bit image is converted
  to float as is, and affine brightness (a, b) absorbs the changes.

  Exposure: like DSO, the irradiance is NOT divided by the exposure time (that would leave intensity units); the
  exposure is stored in Frame::exposure and enters the brightness transfer a_ji (AffineBrightness::transfer).

  Pyramid depth follows DSO's rule (setGlobalCalib): halve while the current level keeps more than
  Tracker::minCoarsestPixels pixels, up to Tracker::maxPyramidLevels levels.

  Threading: used by the tracking thread only. process() reuses its scratch images; each returned Frame owns
  its own pyramid (frames outlive the call: keyframes, mapping queue). Frames come from a small pool: a pooled
  frame that nobody else holds any more (its std::shared_ptr count is 1) is reused with its buffers, so the
  steady state allocates no pyramid per frame.
*/
#ifndef HSLAM_SYSTEM_FRAME_PREPROCESSOR_H
#define HSLAM_SYSTEM_FRAME_PREPROCESSOR_H

#include "features/ImagePyramid.h"
#include "map/Frame.h"

#include <visp3/core/vpCameraParameters.h>
#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImage.h>
#include <visp3/hslam/vpHSlamCamera.h>
#include <visp3/hslam/vpHSlamParameters.h>
#include <visp3/hslam/vpHSlamPhotometricCalibration.h>
#include <visp3/hslam/vpHSlamRectifier.h>

#include <vector>

namespace hslam
{
class VISP_EXPORT FramePreprocessor
{
public:
  /*!
    \param camera : calibration of the raw images.
    \param photometric : photometric calibration (may be empty).
    \param usePhotometric : false ignores \e photometric (affine brightness only).
    \param tracker : pyramid settings.
    \exception vpHSlamException from the rectifier when no pinhole target can be built.
  */
  FramePreprocessor(const vpHSlamCamera &camera, const vpHSlamPhotometricCalibration &photometric, bool usePhotometric,
                    const vpHSlamParameters::Tracker &tracker);

  /*!
    Build the frame of one image.
    \param I : raw image of the camera's input size.
    \param timestamp : seconds.
    \param exposure : exposure time, <= 0 or non-finite when unknown (then 1).
    \param id : index of the frame in the input sequence.
    \exception vpHSlamException::invalidImage when I is empty or its size is not the calibration's (both named).
  */
  FramePtr process(const vpImage<unsigned char> &I, double timestamp, double exposure, int id);

  //! Level-0 intrinsics of the rectified image.
  const PinholeIntrinsics &intrinsics() const { return m_K0; }
  vpCameraParameters getCameraParameters() const { return m_rectifier.getCameraParameters(); }
  int width() const { return static_cast<int>(m_rectifier.getWidth()); }
  int height() const { return static_cast<int>(m_rectifier.getHeight()); }
  //! Pyramid levels of every frame (DSO rule, see the file comment).
  int pyramidLevels() const { return m_levels; }
  //! True when a response or vignette is applied.
  bool usesPhotometricCalibration() const { return m_usePhotometric; }

private:
  vpHSlamRectifier m_rectifier;
  vpHSlamPhotometricCalibration m_photometric;
  bool m_usePhotometric;
  PinholeIntrinsics m_K0;
  int m_levels;
  int m_maxLevels, m_minCoarsestPixels;
  unsigned int m_inputWidth, m_inputHeight;
  vpImage<float> m_irradianceInput; //!< scratch: G(I)/V in the input geometry
  vpImage<float> m_intensity;       //!< scratch: rectified irradiance
  std::vector<FramePtr> m_pool;     //!< frames reused once released by tracking and mapping
};
} // namespace hslam

#endif
