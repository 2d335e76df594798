/*
 * H-SLAM for ViSP.
 */
/*!
  \file vpHSlamPhotometricCalibration.h
  \brief Inverse response, vignette and exposure: from 8-bit pixels to irradiance.
*/
#ifndef VP_HSLAM_PHOTOMETRIC_CALIBRATION_H
#define VP_HSLAM_PHOTOMETRIC_CALIBRATION_H

#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImage.h>

#include <string>
#include <vector>

/*!
  \class vpHSlamPhotometricCalibration
  \ingroup group_hslam
  \brief Photometric calibration of a camera (TUM monoVO convention): inverse response G, vignette V, exposure t.

  What it is for: the direct part of H-SLAM compares intensities across frames; with a calibration, each 8-bit
  pixel value I at pixel x is turned into irradiance B(x) = G(I(x)) / (t V(x)) before any comparison (DSO's
  photometric model, Engel et al. 2016, eq. 1 of the TUM monoVO paper). Without one, the system estimates an
  affine brightness change (a, b) per frame instead. Absence is therefore a normal mode, not an error:
  hasResponse() / hasVignette() say what is known and getStatus() gives a one-line description for the caller to
  report once.

  Files:
  - `pcalib.txt`: 256 whitespace-separated values, G(0) ... G(255), non-decreasing. They are rescaled so that
    G(0) = 0 and G(255) = 255 (DSO convention) so irradiance stays in intensity units.
  - vignette: an 8- or 16-bit grey PNG of the input image size; values are divided by their maximum so V is in
    (0, 1].
  - exposure: per frame, from the image source (milliseconds in TUM monoVO's times.txt); any positive unit works
    as long as it is consistent within a sequence. A non-positive or unknown exposure means "use 1".

  Malformed files (wrong count, non-monotonic G, wrong vignette size, non-positive vignette) raise
  vpHSlamException naming the file and the problem.

  Threading: immutable after load; toIrradiance() is const and may run from several threads at once.

  \code
  vpHSlamPhotometricCalibration calib;
  calib.load("pcalib.txt", "vignette.png", 1280, 1024); // either path may be empty
  vpImage<float> B;
  calib.toIrradiance(I, exposureMs, B);
  \endcode
*/
class VISP_EXPORT vpHSlamPhotometricCalibration
{
public:
  //! No calibration: identity response, no vignette.
  vpHSlamPhotometricCalibration();

  /*!
    Load a calibration. Either path may be empty (that part stays identity).
    \param responseFile : `pcalib.txt` path or empty.
    \param vignetteFile : vignette PNG path or empty.
    \param width, height : expected vignette size (input image size, pixels).
    \exception vpHSlamException::fileNotFound, fileUnreadable, parseError or invalidCalibration, naming the file.
  */
  void load(const std::string &responseFile, const std::string &vignetteFile, unsigned int width,
            unsigned int height);

  //! Set the inverse response directly (256 values, non-decreasing); rescaled as for files.
  void setInverseResponse(const std::vector<double> &G);
  //! Set the vignette directly (values > 0, any scale; normalised to a maximum of 1).
  void setVignette(const vpImage<float> &V);

  bool hasResponse() const { return !m_G.empty(); }
  bool hasVignette() const { return m_invV.getSize() > 0; }
  //! True when neither response nor vignette is known (affine brightness will be estimated instead).
  bool isEmpty() const { return !hasResponse() && !hasVignette(); }

  //! The 256 rescaled inverse response values (empty when unknown).
  const std::vector<float> &getInverseResponse() const { return m_G; }

  /*!
    Irradiance image B = G(I) / (t V), same size as I.
    \param I : raw 8-bit image in the INPUT geometry (before rectification: the vignette lives there).
    \param exposure : exposure time of this frame (any consistent unit); <= 0 means unknown (use 1).
    \param B : output, resized only when its size differs (no allocation per frame otherwise).
    \exception vpHSlamException::invalidImage if a vignette is loaded and I's size differs from it.
  */
  void toIrradiance(const vpImage<unsigned char> &I, double exposure, vpImage<float> &B) const;

  //! One line saying what is calibrated, e.g. "photometric calibration: none (affine brightness estimated)".
  std::string getStatus() const;

private:
  std::vector<float> m_G;  //!< inverse response, 256 values
  vpImage<float> m_invV;   //!< 1 / vignette, precomputed
  std::string m_responseFile, m_vignetteFile;
};

#endif
