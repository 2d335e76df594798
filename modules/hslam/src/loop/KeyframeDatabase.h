/*
 * H-SLAM for ViSP.
 */
/*!
  \file KeyframeDatabase.h
  \brief Keyframe database for place recognition: BoW vectors of keyframes, an inverted index (word -> keyframes)
  and queries that return scored, co-visibility-grouped candidates (paper section 3.4; ORB-SLAM2's
  KeyFrameDatabase, whose rules and constants are the defaults here).

  A query (relocalisation of a lost frame, loop detection for a new keyframe) runs in four steps:
  1. keyframes sharing at least one word with the query are found through the inverted index, minus the ones the
     caller excludes (for loops: keyframes connected to the query keyframe);
  2. only those sharing at least minCommonWordsRatio times the largest number of shared words are scored (L1);
     scores below Query::minScore, or below Query::minNormalizedScore once divided by Query::expectedScore, drop;
  3. when the caller gives co-visibility, each candidate's group score is its score plus the scores of its best
     co-visible neighbours that are candidates too, and the group is represented by its best-scoring member
     (ORB-SLAM2: a place seen by several keyframes is more reliable than a single lucky one);
  4. groups scoring at least groupRetainRatio times the best group are returned, best first.

  The expected score normalises raw scores, which depend on the scene's texture, into "how much like its own
  neighbourhood": the caller passes the score of the query with its best co-visible neighbour (scoresWith()
  computes it from vectors stored here); DBoW2's loop detector does the same with the previous image.

  Threading: every method may be called from any thread; queries share a lock, add/remove/clear take it
  exclusively. The co-visibility and exclusion callbacks run under the shared lock and must not modify the database.
*/
#ifndef HSLAM_LOOP_KEYFRAME_DATABASE_H
#define HSLAM_LOOP_KEYFRAME_DATABASE_H

#include "features/BowVector.h"

#include <visp3/core/vpConfig.h>

#include <cstddef>
#include <functional>
#include <shared_mutex>
#include <unordered_map>
#include <vector>

namespace hslam
{
//! Settings of KeyframeDatabase queries (defaults: ORB-SLAM2's KeyFrameDatabase).
struct KeyframeDatabaseOptions {
  double minCommonWordsRatio = 0.8; //!< score only keyframes sharing this fraction of the most words shared
  double groupRetainRatio = 0.75;   //!< keep groups scoring at least this fraction of the best group
  int groupNeighbours = 10;         //!< co-visible neighbours summed into a candidate's group score
};

class VISP_EXPORT KeyframeDatabase
{
public:
  using KeyframeId = int;

  //! One answer to a query.
  struct Candidate {
    KeyframeId id = -1;           //!< best-scoring keyframe of its group
    double score = 0.0;           //!< L1 score of that keyframe with the query, in [0, 1]
    double normalizedScore = 0.0; //!< score / expected score (= score when no expected score was given)
    double groupScore = 0.0;      //!< sum of scores over the group (= score without co-visibility)
    int commonWords = 0;          //!< words shared with the query
  };

  //! What to ask.
  struct Query {
    //! Keyframes never returned (for loops: the query's co-visible neighbours). Empty: none.
    std::function<bool(KeyframeId)> excluded;
    /*!
      Best co-visible neighbours of a keyframe, best first (only the first KeyframeDatabaseOptions::groupNeighbours
      are used). Empty: no grouping, every candidate is its own group.
    */
    std::function<std::vector<KeyframeId>(KeyframeId)> covisible;
    double minScore = 0.0;           //!< raw L1 score floor (ORB-SLAM2 loops: lowest score with the neighbours)
    double expectedScore = 0.0;      //!< > 0: normalise scores by it (score with the best co-visible neighbour)
    double minNormalizedScore = 0.0; //!< floor on the normalised score
    std::size_t maxCandidates = 0;   //!< 0: all that pass
  };

  explicit KeyframeDatabase(std::size_t wordCount, const KeyframeDatabaseOptions &options = KeyframeDatabaseOptions());

  /*!
    Add a keyframe's BoW vector.
    \exception vpHSlamException::invalidArgument when the id is already present or a word id is out of the
    vocabulary.
  */
  void add(KeyframeId id, const BowVector &bow);
  //! Remove a keyframe (culled or reset). Returns false when it was not present.
  bool remove(KeyframeId id);
  void clear();
  std::size_t size() const;
  bool contains(KeyframeId id) const;
  std::size_t wordCount() const { return m_wordCount; }
  const KeyframeDatabaseOptions &options() const { return m_options; }
  //! Bytes held on the heap: the inverted index and the stored vectors, allocator overhead included.
  double memoryBytes() const;

  //! Candidates for \e bow, best first (see the class comment).
  std::vector<Candidate> query(const BowVector &bow, const Query &query) const;

  //! The stored BoW vector of keyframe \e id; false when absent.
  bool vectorOf(KeyframeId id, BowVector &bow) const;

  //! L1 scores of \e bow with each stored keyframe of \e ids (absent ids are skipped).
  std::vector<double> scoresWith(const BowVector &bow, const std::vector<KeyframeId> &ids) const;

private:
  //! A keyframe's slot in m_slots and the count of words it shares with a query.
  struct SharedWords {
    std::uint32_t slot;
    int count;
  };
  //! Every keyframe sharing a word with \e bow, with how many it shares (caller holds the lock).
  std::vector<SharedWords> sharedWordCounts(const BowVector &bow) const;
  struct Word;
  //! The keyframe of \e keyframeSlot as a holder of \e word, and out of it (caller holds the lock exclusively).
  void addHolder(Word &word, std::uint32_t keyframeSlot);
  void removeHolder(Word &word, std::uint32_t keyframeSlot);
  //! The word's chained holders into a list of their own (caller holds the lock exclusively).
  void moveChainToList(Word &word);

  KeyframeDatabaseOptions m_options;
  mutable std::shared_mutex m_mutex;
  std::size_t m_wordCount = 0; //!< words of the vocabulary
  //! The inverted index: for each word some keyframe holds, where its holders are (a map: one empty list per word of
  //! the shipped vocabulary's 413,203 took 10 MB before the first keyframe). A word's first holders are a chain
  //! through m_holders (one pool for all words): a word held by one keyframe, the common case, costs a hash node and
  //! 8 bytes instead of a hash node and a vector (80 bytes a word and keyframe before: most of what a stored
  //! keyframe's place recognition took). Past kChainedHolders holders the word's holders move to a list of their own
  //! in m_lists, read in one sweep: walking long chains, whose links lie all over the pool, was three quarters of a
  //! query at 10,000 stored keyframes of a room revisited lap after lap (every word held by hundreds of keyframes).
  static constexpr std::uint32_t kNoHolder = 0xffffffffu;
  struct Word {
    std::uint32_t chain;       //!< first holder in m_holders, kNoHolder when none
    std::uint32_t chainLength; //!< holders in the chain
    std::uint32_t list;        //!< index in m_lists, kNoList while the word's holders are chained
  };
  struct Holder {
    std::uint32_t slot; //!< the keyframe's slot in m_slots
    std::uint32_t next; //!< next holder of the same word in m_holders, kNoHolder at the end
  };
  static constexpr std::uint32_t kChainedHolders = 8;
  static constexpr std::uint32_t kNoList = 0xffffffffu;
  std::unordered_map<std::uint32_t, Word> m_index;
  std::vector<std::vector<std::uint32_t>> m_lists; //!< keyframe slots holding a word, in no order
  std::vector<std::uint32_t> m_freeLists;          //!< entries of m_lists released by remove()
  std::vector<Holder> m_holders;
  std::uint32_t m_freeHolders = kNoHolder; //!< chain of the entries of m_holders freed by remove()
  //! Keyframes by slot, a dense numbering reused after remove(): a query counts shared words in an array indexed by
  //! slot instead of a hash map keyed by keyframe (a room revisited lap after lap has every word held by hundreds of
  //! keyframes, and the hash map's counting was most of a query at thousands of stored keyframes).
  struct Slot {
    KeyframeId id = -1; //!< -1 with an empty vector: a free slot
    BowVector bow;
  };
  std::vector<Slot> m_slots;
  std::unordered_map<KeyframeId, std::uint32_t> m_slotOf; //!< stored keyframe -> its slot
  std::vector<std::uint32_t> m_freeSlots;
  //! Heap bytes of the nodes of m_index and m_slotOf and of the stored vectors, kept up to date by add(), remove() and
  //! clear(), so that memoryBytes() (called after every keyframe for the statistics) does not walk an index of 10^5
  //! words.
  double m_heapBytes = 0.;
};
} // namespace hslam

#endif
