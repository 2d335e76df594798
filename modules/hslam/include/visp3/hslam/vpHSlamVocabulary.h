/*
 * H-SLAM for ViSP.
 */
/*!
  \file vpHSlamVocabulary.h
  \brief ORB vocabulary tree for place recognition: load, save, describe, and the BoW similarity of two images.
*/
#ifndef VP_HSLAM_VOCABULARY_H
#define VP_HSLAM_VOCABULARY_H

#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImage.h>

#include <cstdint>
#include <memory>
#include <string>

namespace hslam
{
class OrbVocabulary;
}

/*!
  \class vpHSlamVocabulary
  \ingroup group_hslam
  \brief A bag-of-words vocabulary over 256-bit ORB descriptors (hierarchical k-means tree, TF-IDF weights, L1
  score), as used by H-SLAM's relocalisation and loop closure.

  What it is for: place recognition describes an image by the histogram of the vocabulary words its ORB features
  fall into, and compares images by the L1 score of the histograms (1 = same words in the same proportions,
  0 = nothing in common). The module ships a default vocabulary (data/hslam-orb.hvoc in the source tree,
  share/hslam/ once installed; defaultPath() finds it), trained with tutorial-hslam-vocabulary on images that are
  not the evaluation sequences; train your own on your environment with vpHSlamVocabularyTrainer or that program.

  Files: H-SLAM's compact binary format (versioned, checksummed; a 10^6-word vocabulary loads in a few tens of
  milliseconds), DBoW2's text format (ORB-SLAM2's ORBvoc.txt) and DBoW2's OpenCV YAML (plain or .gz), so a
  vocabulary you already have can be used, or converted once to the binary format for fast loading.

  Threading: a loaded vocabulary is immutable; const methods may be called from any number of threads.

  \code
  vpHSlamVocabulary voc = vpHSlamVocabulary::load(vpHSlamVocabulary::defaultPath());
  std::cout << voc.describe() << std::endl;
  double s = voc.score(I1, I2);                           // 0..1
  voc.save("ORBvoc.hvoc", vpHSlamVocabulary::formatBinary); // e.g. after loading ORBvoc.txt once
  \endcode
*/
class VISP_EXPORT vpHSlamVocabulary
{
public:
  //! File layouts.
  enum FileFormat {
    formatAuto,      //!< detect on load from the first bytes; binary on save
    formatBinary,    //!< H-SLAM binary (.hvoc)
    formatDbow2Text, //!< DBoW2 / ORB-SLAM2 text (ORBvoc.txt layout)
    formatDbow2Yaml  //!< DBoW2 OpenCV YAML, gzip-compressed when the name ends with .gz
  };

  //! An empty vocabulary (empty() is true).
  vpHSlamVocabulary();
  ~vpHSlamVocabulary();
  vpHSlamVocabulary(const vpHSlamVocabulary &other);                //!< deep copy
  vpHSlamVocabulary &operator=(const vpHSlamVocabulary &other);     //!< deep copy
  vpHSlamVocabulary(vpHSlamVocabulary &&other) noexcept;            //!< leaves \e other empty
  vpHSlamVocabulary &operator=(vpHSlamVocabulary &&other) noexcept; //!< swaps with \e other

  /*!
    Read a vocabulary file.
    \exception vpHSlamException naming the file and the problem: fileNotFound, fileUnreadable, parseError (wrong
    magic, truncated, checksum mismatch, empty, not a tree), unsupported (descriptor size other than 32 bytes, a
    newer format version).
  */
  static vpHSlamVocabulary load(const std::string &path, FileFormat format = formatAuto);
  /*!
    Write the vocabulary (through a temporary file renamed at the end).
    \exception vpHSlamException::invalidArgument when empty, fileUnreadable when the file cannot be written.
  */
  void save(const std::string &path, FileFormat format = formatBinary) const;

  /*!
    Path of the shipped default vocabulary: $HSLAM_VOCABULARY when set, else the installed copy, else the source
    tree's data/ folder; empty when none exists.
  */
  static std::string defaultPath();
  //! Parse "auto", "binary", "text", "yaml". \exception vpHSlamException::invalidArgument otherwise.
  static FileFormat parseFormat(const std::string &name);

  bool empty() const;                   //!< true until loaded or trained
  unsigned int getBranching() const;    //!< k
  unsigned int getLevels() const;       //!< L
  std::size_t getWordCount() const;     //!< leaves
  std::size_t getNodeCount() const;     //!< nodes, root included
  std::uint64_t getFingerprint() const; //!< identifies the tree and weights (0 when empty)
  //! One line: k, L, words, nodes, weighting.
  std::string describe() const;

  /*!
    L1 score of the BoW vectors of two images (ORB features detected with the defaults of the
    place-recognition front end), in [0, 1]. A convenience for tests and exploration; the system computes vectors
    once per keyframe.
  */
  double score(const vpImage<unsigned char> &I1, const vpImage<unsigned char> &I2) const;

  //! The implementation (for the module's own code; not part of the stable API).
  const hslam::OrbVocabulary &impl() const;
  //! Wrap an implementation object (for the module's own code).
  explicit vpHSlamVocabulary(const hslam::OrbVocabulary &vocabulary);

private:
  std::unique_ptr<hslam::OrbVocabulary> m_impl;
};

#endif
