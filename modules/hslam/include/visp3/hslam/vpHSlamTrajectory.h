/*
 * H-SLAM for ViSP.
 */
/*!
  \file vpHSlamTrajectory.h
  \brief A timestamped camera trajectory (camera-to-world poses) with TUM, KITTI and EuRoC readers and writers.
*/
#ifndef VP_HSLAM_TRAJECTORY_H
#define VP_HSLAM_TRAJECTORY_H

#include <visp3/core/vpConfig.h>
#include <visp3/core/vpHomogeneousMatrix.h>

#include <string>
#include <vector>

/*!
  \class vpHSlamTrajectory
  \ingroup group_hslam
  \brief Ordered list of (timestamp in seconds, camera-to-world pose wMc) with the common file formats.

  What it is for: the SLAM system saves its estimate through it, and the evaluation (vpHSlamTrajectoryEvaluator)
  reads an estimate and a ground truth through it. Formats:
  - TUM: one line "t tx ty tz qx qy qz qw" (Hamilton quaternion, camera-to-world), '#' comments, any blanks.
    A quaternion whose norm is off 1 by more than 1e-3 is an error; otherwise it is normalised.
  - KITTI odometry: 12 numbers per line, the 3x4 matrix [R | t] of wMc row by row; timestamps come from an
    optional times file, else from a frame rate, else the row index.
  - EuRoC ASL ground truth csv: time in ns, position, quaternion w x y z of the BODY (IMU) frame; camera poses are
    obtained with the sensor.yaml extrinsics T_BS: wMc = wMb * T_BS.

  Readers require strictly increasing timestamps and name file:line in every error (vpHSlamException). Writers
  flush and check the stream, so a trajectory saved on exit is complete or an error is thrown.

  Threading and ownership: a plain value type (copyable); not synchronised, use from one thread at a time.

  \code
  vpHSlamTrajectory gt = vpHSlamTrajectory::readEurocGroundTruth("mav0/state_groundtruth_estimate0/data.csv",
                                                                 "mav0/cam0/sensor.yaml");
  vpHSlamTrajectory est;
  est.add(1403715273.262, slam.get_cMw().inverse());
  est.saveTum("estimate.txt");
  \endcode
*/
class VISP_EXPORT vpHSlamTrajectory
{
public:
  //! File formats understood by load() and save().
  enum Format {
    formatTum,   //!< "t tx ty tz qx qy qz qw"
    formatKitti, //!< 12 numbers per line (3x4 wMc), no timestamps in the file
    formatEuroc  //!< EuRoC ground-truth csv (body frame; read only)
  };

  vpHSlamTrajectory();

  //! Append a pose; \e timestamp in seconds, \e wMc camera-to-world. Order is not checked (see isSorted()).
  void add(double timestamp, const vpHomogeneousMatrix &wMc);
  //! Remove every pose.
  void clear();
  //! Number of poses.
  size_t size() const { return m_timestamps.size(); }
  //! True when there is no pose.
  bool empty() const { return m_timestamps.empty(); }
  //! Timestamp of pose \e i, seconds.
  double getTimestamp(size_t i) const { return m_timestamps.at(i); }
  //! Camera-to-world pose \e i.
  const vpHomogeneousMatrix &get_wMc(size_t i) const { return m_wMc.at(i); }
  //! All timestamps, seconds.
  const std::vector<double> &getTimestamps() const { return m_timestamps; }
  //! All camera-to-world poses.
  const std::vector<vpHomogeneousMatrix> &getPoses() const { return m_wMc; }
  //! True when timestamps increase strictly.
  bool isSorted() const;
  //! Sort poses by timestamp (stable).
  void sortByTimestamp();

  //! Replace every pose wMc by wMc * cMs (e.g. body to camera with EuRoC T_BS = bMc).
  void transformRight(const vpHomogeneousMatrix &cMs);
  //! Replace every pose wMc by aMw * wMc (change of world frame).
  void transformLeft(const vpHomogeneousMatrix &aMw);
  //! The poses whose timestamps lie in [\e from, \e to] seconds, in their order (e.g. to compare with a system that
  //! starts later). \throw vpHSlamException when \e from > \e to or either is NaN.
  vpHSlamTrajectory timeSpan(double from, double to) const;

  //! Read a TUM trajectory. \throw vpHSlamException naming file:line.
  static vpHSlamTrajectory readTum(const std::string &path);
  /*!
    Read a KITTI trajectory.
    \param path : the poses file.
    \param timesPath : optional times file (one time in seconds per line, as many as poses).
    \param frameRate : without times file, timestamps are index / frameRate if frameRate > 0, else the index.
  */
  static vpHSlamTrajectory readKitti(const std::string &path, const std::string &timesPath = "", double frameRate = 0.);
  //! Read an EuRoC ground-truth csv as BODY (IMU) poses wMb.
  static vpHSlamTrajectory readEurocGroundTruth(const std::string &csvPath);
  //! Read an EuRoC ground-truth csv and convert it to camera poses with T_BS from \e sensorYamlPath (wMc = wMb bMc).
  static vpHSlamTrajectory readEurocGroundTruth(const std::string &csvPath, const std::string &sensorYamlPath);
  //! Read T_BS (camera-to-body, bMc) from an EuRoC sensor.yaml (cv::FileStorage).
  static vpHomogeneousMatrix readEurocSensorExtrinsics(const std::string &sensorYamlPath);
  //! Read any supported format (KITTI: row index as timestamp).
  static vpHSlamTrajectory load(const std::string &path, Format format);
  //! Parse "tum", "kitti" or "euroc". \throw vpHSlamException (invalidArgument) otherwise.
  static Format formatFromString(const std::string &name);

  //! Write in TUM format (9 decimals of seconds, 10 significant digits of translation, 9 decimals of quaternion).
  void saveTum(const std::string &path) const;
  //! Write in KITTI format (12 numbers, 9 decimals in scientific notation); timestamps are not written.
  void saveKitti(const std::string &path) const;
  //! Write in TUM or KITTI format. \throw vpHSlamException (unsupported) for EuRoC.
  void save(const std::string &path, Format format) const;

private:
  std::vector<double> m_timestamps;       //!< seconds
  std::vector<vpHomogeneousMatrix> m_wMc; //!< camera-to-world poses
};

#endif
