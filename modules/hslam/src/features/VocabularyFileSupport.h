/*
 * H-SLAM for ViSP.
 */
/*!
  \file VocabularyFileSupport.h
  \brief Helpers shared by the vocabulary readers (VocabularyFiles.cpp, VocabularyYaml.cpp); not a public API.
*/
#ifndef HSLAM_FEATURES_VOCABULARY_FILE_SUPPORT_H
#define HSLAM_FEATURES_VOCABULARY_FILE_SUPPORT_H

#include "features/BinaryDescriptor.h"

#include <cstddef>
#include <string>

namespace hslam
{
//! DBoW2's own bounds on the scoring and weighting fields (TemplatedVocabulary::loadFromTextFile).
constexpr int kDbow2MaxScoring = 5;
constexpr int kDbow2MaxWeighting = 3;

//! The whole file; vpHSlamException naming it when missing, a folder, unreadable or empty.
std::string readVocabularyFile(const std::string &path);

//! Parse "b0 b1 ... b31" (DBoW2 FORB::toString); \e what names the place for errors.
OrbDescriptor descriptorFromText(const std::string &text, const std::string &path, std::size_t line,
                                 const std::string &what);
} // namespace hslam

#endif
