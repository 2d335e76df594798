/*
 * H-SLAM for ViSP.
 */
/*!
  \file VocabularyFiles.h
  \brief Reading and writing OrbVocabulary files: H-SLAM's binary format, DBoW2's text format (ORB-SLAM2's
  ORBvoc.txt layout) and DBoW2's OpenCV YAML (plain or gzip-compressed).

  H-SLAM binary format, version 1 (".hvoc"), all integers little-endian:
  \verbatim
  offset  size        field
  0       8           magic "HSLAMVOC"
  8       4           format version (1)
  12      4           descriptor size in bytes (32: 256-bit ORB)
  16      4           branching factor k
  20      4           depth L
  24      4           weighting (DBoW2 numbering: 0 TF-IDF, 1 TF, 2 IDF, 3 binary)
  28      4           scoring (DBoW2 numbering; H-SLAM scores with L1 = 0)
  32      4           node count N, root included
  36      4           word count W
  40      36 (N-1)    nodes 1..N-1: parent (uint32), centroid (32 bytes, OpenCV row order)
  ...     12 W        words 0..W-1: node (uint32), weight (IEEE-754 double)
  ...     8           checksum: hashBytes() of every byte before it
  \endverbatim
  Loading reads the file in one go, checks size, magic, version, descriptor size and checksum before parsing, then
  validates the tree (OrbVocabulary::assign), so a 10^6-word vocabulary loads in a few tens of milliseconds.

  DBoW2 text: a first line "k L scoring weighting", then one line per node after the root, in node order:
  "parent isLeaf b0 ... b31 weight"; words are numbered in the order of their leaves.
  DBoW2 YAML: the cv::FileStorage layout of TemplatedVocabulary::save (vocabulary: k, L, scoringType,
  weightingType, nodes [{nodeId, parentId, weight, descriptor}], words [{wordId, nodeId}]).

  Errors (missing, truncated, corrupt, wrong magic or descriptor size, empty, not a tree) are vpHSlamException
  naming the file and the problem.
*/
#ifndef HSLAM_FEATURES_VOCABULARY_FILES_H
#define HSLAM_FEATURES_VOCABULARY_FILES_H

#include "features/OrbVocabulary.h"

#include <string>

namespace hslam
{
//! File layouts a vocabulary can be read from and written to.
enum class VocabularyFormat { automatic, binary, dbow2Text, dbow2Yaml };

//! Format from the file's first bytes: binary magic, gzip or "%YAML" (YAML), anything else text.
VISP_EXPORT VocabularyFormat detectVocabularyFormat(const std::string &path);

VISP_EXPORT OrbVocabulary loadVocabulary(const std::string &path,
                                         VocabularyFormat format = VocabularyFormat::automatic);
//! Writes through a temporary file renamed at the end: an interrupted save never leaves a half file behind.
VISP_EXPORT void saveVocabulary(const OrbVocabulary &vocabulary, const std::string &path, VocabularyFormat format);

VISP_EXPORT OrbVocabulary loadVocabularyBinary(const std::string &path);
VISP_EXPORT OrbVocabulary loadVocabularyDbow2Text(const std::string &path);
VISP_EXPORT OrbVocabulary loadVocabularyDbow2Yaml(const std::string &path);
} // namespace hslam

#endif
