/*
 * H-SLAM for ViSP.
 */
/*!
  \file vpHSlamException.h
  \brief Error type thrown by the visp_hslam module on bad input or misuse.
*/
#ifndef VP_HSLAM_EXCEPTION_H
#define VP_HSLAM_EXCEPTION_H

#include <visp3/core/vpConfig.h>
#include <visp3/core/vpException.h>

#include <string>

/*!
  \defgroup group_hslam H-SLAM module
  Monocular hybrid (direct + feature-based) visual SLAM for ViSP (module visp_hslam).

  The system class vpHSlam takes grey images with their timestamps from any vpHSlamImageSource (datasets, video
  files, a live V4L2 camera) and a vpHSlamCamera description, and estimates camera poses (vpHomogeneousMatrix)
  and a map. vpHSlamParameters holds every option; vpHSlamTrajectory and vpHSlamTrajectoryEvaluator read, write
  and score trajectories (ATE, RPE). Errors are reported as vpHSlamException.

  (ViSP modules keep their documentation in their headers; the group is declared once, here, beside the module's
  error type.)
*/

/*!
  \class vpHSlamException
  \ingroup group_hslam
  \brief Exception thrown by visp_hslam for bad input (missing or malformed files, wrong calibration, empty
  sequences) and for misuse of the API.

  It derives from vpException, so existing ViSP error handling catches it. The message always names what failed
  (a file and, where it applies, a line) and why; getCode() returns one of vpHSlamException::ErrorCode so callers
  can react without parsing text.

  Library code never prints and never exits: every error reaches the caller through this type.

  \code
  try {
    vpHSlamCamera cam = vpHSlamCamera::load("camera.txt");
  } catch (const vpHSlamException &e) {
    if (e.getCode() == vpHSlamException::fileNotFound) { ... }
    std::cerr << e.getStringMessage() << std::endl;
  }
  \endcode
*/
class VISP_EXPORT vpHSlamException : public vpException
{
public:
  //! What went wrong. Values start above vpException's generic codes.
  enum ErrorCode {
    fileNotFound = 1000, //!< A file or folder that must exist does not.
    fileUnreadable,      //!< The file exists but cannot be opened or decoded (e.g. a corrupt image).
    parseError,          //!< A line or field cannot be parsed.
    invalidCalibration,  //!< Calibration values are inconsistent (sizes, counts, monotonicity, ranges).
    invalidImage,        //!< An image has the wrong size or is empty.
    invalidTimestamps,   //!< Timestamps are not strictly increasing or do not match the image list.
    invalidArgument,     //!< A parameter or argument is out of range.
    unsupported,         //!< A format or model this build does not handle.
    deviceError,         //!< A live device cannot be opened or delivers unexpected frames.
    endOfSequence        //!< A source was read past its last frame.
  };

  /*!
    Build an exception.
    \param code : one of ErrorCode.
    \param message : what failed and why; name the file (and line) when there is one.
  */
  vpHSlamException(ErrorCode code, const std::string &message);
  ~vpHSlamException() override;
};

#endif
