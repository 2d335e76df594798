/*
 * H-SLAM for ViSP.
 */
/*!
  \file vpHSlamTag.h
  \brief The AprilTag that gives a SLAM run metres and, optionally, its world frame.
*/
#ifndef VP_HSLAM_TAG_H
#define VP_HSLAM_TAG_H

#include <visp3/core/vpConfig.h>

#include <string>
#include <vector>

/*!
  \class vpHSlamTag
  \ingroup group_hslam
  \brief Description of a printed AprilTag (family, size, optionally the id of the tag that defines the world frame).

  What it is for: a monocular map has no unit and an arbitrary world frame. Given to vpHSlam::setTag(), the tag is
  detected in keyframes (ViSP's vpDetectorAprilTag), and its poses there against the keyframes' SLAM poses give the
  similarity that makes the output metric (docs/metric-tag-frame.md). With an id, the output is also expressed in that
  tag's frame (the frame of vpDetectorAprilTag::getPose(): origin at the tag's centre, x to the right and y up as
  printed, z out of the tag towards the camera), the way ViSP programs place a robot's goal.

  Size: the side of the tag's black square in metres, as vpDetectorAprilTag::detect() takes it (for tag36h11, 8 of
  its 10 cells; measure the print, printers scale).

  Families: those of ViSP's detector in Debian's build: tag36h11 (recommended), tag25h9, tag16h5, tagCircle21h7.

  \code
  vpHSlam slam(*source, params);
  slam.setTag(vpHSlamTag::parse("tag36h11:0.16:0")); // 16 cm tag, id 0 defines the world frame
  \endcode
*/
class VISP_EXPORT vpHSlamTag
{
public:
  //! No tag (isSet() is false).
  vpHSlamTag();
  /*!
    \param family : one of familyNames().
    \param size : side of the black square, metres (> 0, finite).
    \param id : id of the tag that defines the world frame, or -1: any tag of the family gives the scale only.
    \exception vpHSlamException::invalidArgument naming the value for an unknown family, a size not positive or an
    id below -1.
  */
  vpHSlamTag(const std::string &family, double size, int id = -1);

  /*!
    From the command-line form FAMILY:SIZE[:ID], e.g. "tag36h11:0.16" or "tag36h11:0.16:3".
    \exception vpHSlamException::invalidArgument naming the text and the expected form.
  */
  static vpHSlamTag parse(const std::string &text);
  //! Families this build detects.
  static std::vector<std::string> familyNames();

  bool isSet() const { return !m_family.empty(); }          //!< a tag was described
  const std::string &getFamily() const { return m_family; } //!< e.g. "tag36h11" (empty when not set)
  double getSize() const { return m_size; }                 //!< side of the black square, metres
  int getId() const { return m_id; }                        //!< id defining the world frame, -1: scale only
  bool hasId() const { return m_id >= 0; }                  //!< an id defines the world frame
  //! The FAMILY:SIZE[:ID] form (parse() reads it back); "none" when not set.
  std::string toString() const;

private:
  std::string m_family;
  double m_size = 0.;
  int m_id = -1;
};

#endif
