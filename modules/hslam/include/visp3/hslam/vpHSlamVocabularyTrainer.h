/*
 * H-SLAM for ViSP.
 */
/*!
  \file vpHSlamVocabularyTrainer.h
  \brief Trains a vpHSlamVocabulary from images.
*/
#ifndef VP_HSLAM_VOCABULARY_TRAINER_H
#define VP_HSLAM_VOCABULARY_TRAINER_H

#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImage.h>
#include <visp3/hslam/vpHSlamVocabulary.h>

#include <functional>
#include <memory>

/*!
  \class vpHSlamVocabularyTrainer
  \ingroup group_hslam
  \brief Collects ORB descriptors from training images, then builds a vocabulary by hierarchical k-means
  (DBoW2's algorithm: k-means++ seeding, bit-majority centroids, TF-IDF weights).

  What it is for: a vocabulary trained on images like the ones you will run on recognises places better. Train on
  many varied images (hundreds to thousands), never on the sequences you evaluate on. The result depends only on the
  images (in the order added), the options and the seed: the same inputs give a byte-identical file.

  Memory: 32 bytes per descriptor kept (a million descriptors: 32 MB). Time: a few seconds to a minute for 10^5 to
  10^6 descriptors with the defaults, on one core.

  Threading: not thread-safe; use from one thread.

  \code
  vpHSlamVocabularyTrainer trainer;           // k = 10, L = 6, 1000 features per image
  for (const std::string &file : files) {
    vpImage<unsigned char> I;
    vpHSlamImageIo::readGrey(file, I);
    trainer.addImage(I);
  }
  vpHSlamVocabulary voc = trainer.train();
  voc.save("my-vocabulary.hvoc");
  \endcode
*/
class VISP_EXPORT vpHSlamVocabularyTrainer
{
public:
  //! Training settings.
  struct Options {
    unsigned int branching = 10;           //!< k: children per node (DBoW2 / ORB-SLAM2: 10)
    unsigned int levels = 6;               //!< L: depth, up to k^L words (ORB-SLAM2: 6, 10^6 words)
    unsigned long long seed = 1;           //!< k-means++ seeding
    unsigned int featuresPerImage = 1000;  //!< ORB features per image (ORB-SLAM2 at 640x480: 1000)
    unsigned int maxKmeansIterations = 30; //!< Lloyd iterations per node at most
  };

  vpHSlamVocabularyTrainer(); //!< default Options
  /*!
    \param options : see Options.
    \exception vpHSlamException::invalidArgument when featuresPerImage is 0.
  */
  explicit vpHSlamVocabularyTrainer(const Options &options);
  ~vpHSlamVocabularyTrainer();

  /*!
    Detect ORB features in a grey image and keep their descriptors.
    \return the number of descriptors added (0 for a blank image).
    \exception vpHSlamException::invalidImage when I is empty.
  */
  unsigned int addImage(const vpImage<unsigned char> &I);
  std::size_t getImageCount() const;      //!< images added so far
  std::size_t getDescriptorCount() const; //!< descriptors kept so far

  /*!
    Build the vocabulary from everything added so far.
    \param progress : optional, called with the fraction done in [0, 1].
    \exception vpHSlamException::invalidArgument with fewer descriptors than k or invalid options.
  */
  vpHSlamVocabulary train(const std::function<void(double)> &progress = std::function<void(double)>()) const;

private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

#endif
