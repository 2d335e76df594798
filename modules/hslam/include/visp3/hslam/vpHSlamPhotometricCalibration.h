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

  Files (TUM monoVO layout, read the way DSO's PhotometricUndistorter reads them):
  - `pcalib.txt`: exactly 256 whitespace-separated values G(0) ... G(255) (one line or several), finite and
    non-decreasing, with G(255) > G(0). They are rescaled affinely so that G(0) = 0 and G(255) = 255 (DSO
    convention), so irradiance stays in intensity units. DSO requires strictly increasing values; flat steps are
    accepted here because they are harmless for a lookup table.
  - vignette: an 8- or 16-bit grey PNG (or PGM) of the input image size, read at its full bit depth; values are
    divided by their maximum so V is in (0, 1]. Every pixel must be > 0 (1/V is precomputed).
  - exposure: per frame, from the image source (milliseconds in TUM monoVO's times.txt); any positive unit works
    as long as it is consistent within a sequence. A non-positive, non-finite or unknown exposure means "use 1".
    Unlike DSO, which keeps t aside and folds it into its affine brightness term, toIrradiance() divides by t
    directly, so two frames of one scene give the same B whatever their exposures.

  Malformed files raise vpHSlamException naming the file and the problem: fileNotFound (missing),
  fileUnreadable (cannot be opened or decoded), parseError (a token of pcalib.txt is not a number, with its line),
  invalidCalibration (wrong count with the count found, NaN/infinite value, decreasing or constant G, wrong
  vignette size, zero/negative/NaN vignette pixel), unsupported (vignette of another pixel type than 8/16-bit).
  load() is all-or-nothing: on an exception the object keeps its previous calibration.

  Threading and ownership: a value type (copyable, owns its tables). Immutable after load(); toIrradiance() is
  const, allocates nothing once B has the right size, and may run from several threads at once.

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
    \param width, height : expected vignette size (input image size, pixels); only used with a vignette.
    \exception vpHSlamException::fileNotFound, fileUnreadable, parseError, invalidCalibration or unsupported,
    naming the file; invalidArgument if a vignette is given with a zero width or height.
  */
  void load(const std::string &responseFile, const std::string &vignetteFile, unsigned int width, unsigned int height);

  /*!
    Set the inverse response directly (256 finite values, non-decreasing, G(255) > G(0)); rescaled as for files.
    \exception vpHSlamException::invalidCalibration otherwise (the calibration is left unchanged).
  */
  void setInverseResponse(const std::vector<double> &G);
  /*!
    Set the vignette directly (non-empty, every value finite and > 0, any scale; normalised to a maximum of 1).
    \exception vpHSlamException::invalidCalibration otherwise (the calibration is left unchanged).
  */
  void setVignette(const vpImage<float> &V);

  bool hasResponse() const { return !m_G.empty(); }         //!< an inverse response G^-1 is known
  bool hasVignette() const { return m_invV.getSize() > 0; } //!< a vignette V is known
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
  std::vector<float> m_G; //!< inverse response, 256 values
  vpImage<float> m_invV;  //!< 1 / vignette, precomputed
  std::string m_responseFile, m_vignetteFile;
};

#endif
