/*
 * H-SLAM for ViSP.
 */
#include "loop/KeyframeDatabase.h"

#include "common/HeapBytes.h"
#include "features/OrbVocabulary.h"

#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <functional>
#include <mutex>
#include <string>
#include <utility>

namespace hslam
{
namespace
{
//! An entry of \e pool to fill: one released before (listed in \e released), else a new one at its end.
template <typename T> std::uint32_t takeEntry(std::vector<T> &pool, std::vector<std::uint32_t> &released)
{
  if (!released.empty()) {
    const std::uint32_t entry = released.back();
    released.pop_back();
    return entry;
  }
  pool.emplace_back();
  return static_cast<std::uint32_t>(pool.size() - 1);
}
} // namespace

KeyframeDatabase::KeyframeDatabase(std::size_t wordCount, const KeyframeDatabaseOptions &options)
    : m_options(options), m_wordCount(wordCount)
{
  if (!(options.minCommonWordsRatio >= 0.0 && options.minCommonWordsRatio <= 1.0) ||
      !(options.groupRetainRatio >= 0.0 && options.groupRetainRatio <= 1.0) || options.groupNeighbours < 0) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "keyframe database: ratios must lie in [0, 1] and the neighbour count be >= 0");
  }
}

void KeyframeDatabase::add(KeyframeId id, const BowVector &bow)
{
  std::unique_lock<std::shared_mutex> lock(m_mutex);
  if (m_slotOf.count(id)) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "keyframe database: keyframe " + std::to_string(id) + " is already present");
  }
  for (const BowEntry &e : bow) {
    if (e.wordId >= m_wordCount) {
      throw vpHSlamException(vpHSlamException::invalidArgument,
                             "keyframe database: word " + std::to_string(e.wordId) + " of keyframe " +
                                 std::to_string(id) + " is outside the vocabulary (" + std::to_string(m_wordCount) +
                                 " words): built with another vocabulary?");
    }
  }
  using Index = decltype(m_index);
  const std::uint32_t keyframeSlot = takeEntry(m_slots, m_freeSlots);
  for (const BowEntry &e : bow) {
    const auto inserted = m_index.try_emplace(e.wordId, Word{kNoHolder, 0, kNoList});
    m_heapBytes += inserted.second ? hashNodeHeapBytes<Index>() : 0.;
    addHolder(inserted.first->second, keyframeSlot);
  }
  m_slotOf.emplace(id, keyframeSlot);
  m_slots[keyframeSlot] = {id, bow};
  m_heapBytes += hashNodeHeapBytes<decltype(m_slotOf)>() + vectorHeapBytes(m_slots[keyframeSlot].bow);
}

void KeyframeDatabase::addHolder(Word &word, std::uint32_t keyframeSlot)
{
  if (word.list == kNoList && word.chainLength == kChainedHolders) {
    moveChainToList(word);
  }
  if (word.list != kNoList) {
    std::vector<std::uint32_t> &list = m_lists[word.list];
    const double before = vectorHeapBytes(list);
    list.push_back(keyframeSlot);
    m_heapBytes += vectorHeapBytes(list) - before;
    return;
  }
  std::uint32_t holder = m_freeHolders;
  if (holder != kNoHolder) {
    m_freeHolders = m_holders[holder].next;
  } else {
    holder = static_cast<std::uint32_t>(m_holders.size());
    m_holders.push_back(Holder());
  }
  m_holders[holder] = {keyframeSlot, word.chain}; // in front of the word's chain
  word.chain = holder;
  ++word.chainLength;
}

void KeyframeDatabase::removeHolder(Word &word, std::uint32_t keyframeSlot)
{
  if (word.list != kNoList) {
    // Out of the word's list (its order does not matter); an emptied list is released.
    std::vector<std::uint32_t> &list = m_lists[word.list];
    const auto at = std::find(list.begin(), list.end(), keyframeSlot);
    if (at != list.end()) {
      *at = list.back();
      list.pop_back();
    }
    if (list.empty()) {
      m_heapBytes -= vectorHeapBytes(list);
      std::vector<std::uint32_t>().swap(list);
      m_freeLists.push_back(word.list);
      word.list = kNoList;
    }
    return;
  }
  // Unlink the keyframe's entry from the word's chain; it joins the free chain.
  std::uint32_t *link = &word.chain;
  while (*link != kNoHolder && m_holders[*link].slot != keyframeSlot) {
    link = &m_holders[*link].next;
  }
  if (*link != kNoHolder) {
    const std::uint32_t holder = *link;
    *link = m_holders[holder].next;
    m_holders[holder].next = m_freeHolders;
    m_freeHolders = holder;
    --word.chainLength;
  }
}

void KeyframeDatabase::moveChainToList(Word &word)
{
  const std::uint32_t list = takeEntry(m_lists, m_freeLists);
  std::vector<std::uint32_t> &holders = m_lists[list];
  holders.reserve(2 * kChainedHolders);
  for (std::uint32_t h = word.chain; h != kNoHolder;) {
    holders.push_back(m_holders[h].slot);
    const std::uint32_t next = m_holders[h].next;
    m_holders[h].next = m_freeHolders;
    m_freeHolders = h;
    h = next;
  }
  m_heapBytes += vectorHeapBytes(holders);
  word = Word{kNoHolder, 0, list};
}

bool KeyframeDatabase::remove(KeyframeId id)
{
  std::unique_lock<std::shared_mutex> lock(m_mutex);
  const auto it = m_slotOf.find(id);
  if (it == m_slotOf.end()) {
    return false;
  }
  const std::uint32_t keyframeSlot = it->second;
  Slot &slot = m_slots[keyframeSlot];
  for (const BowEntry &e : slot.bow) {
    const auto word = m_index.find(e.wordId);
    if (word == m_index.end()) {
      continue;
    }
    Word &w = word->second;
    removeHolder(w, keyframeSlot);
    if (w.list == kNoList && w.chain == kNoHolder) {
      m_heapBytes -= hashNodeHeapBytes<decltype(m_index)>();
      m_index.erase(word);
    }
  }
  m_heapBytes -= hashNodeHeapBytes<decltype(m_slotOf)>() + vectorHeapBytes(slot.bow);
  m_slotOf.erase(it);
  slot = Slot();
  m_freeSlots.push_back(keyframeSlot);
  return true;
}

void KeyframeDatabase::clear()
{
  std::unique_lock<std::shared_mutex> lock(m_mutex);
  decltype(m_index)().swap(m_index); // clear() would keep the buckets, and the vectors their capacity
  std::vector<Holder>().swap(m_holders);
  m_freeHolders = kNoHolder;
  std::vector<std::vector<std::uint32_t>>().swap(m_lists);
  std::vector<std::uint32_t>().swap(m_freeLists);
  decltype(m_slotOf)().swap(m_slotOf);
  std::vector<Slot>().swap(m_slots);
  std::vector<std::uint32_t>().swap(m_freeSlots);
  m_heapBytes = 0.;
}

std::size_t KeyframeDatabase::size() const
{
  std::shared_lock<std::shared_mutex> lock(m_mutex);
  return m_slotOf.size();
}

bool KeyframeDatabase::contains(KeyframeId id) const
{
  std::shared_lock<std::shared_mutex> lock(m_mutex);
  return m_slotOf.count(id) > 0;
}

bool KeyframeDatabase::vectorOf(KeyframeId id, BowVector &bow) const
{
  std::shared_lock<std::shared_mutex> lock(m_mutex);
  const auto it = m_slotOf.find(id);
  if (it == m_slotOf.end()) {
    return false;
  }
  bow = m_slots[it->second].bow;
  return true;
}

std::vector<double> KeyframeDatabase::scoresWith(const BowVector &bow, const std::vector<KeyframeId> &ids) const
{
  std::shared_lock<std::shared_mutex> lock(m_mutex);
  std::vector<double> scores;
  for (KeyframeId id : ids) {
    const auto it = m_slotOf.find(id);
    if (it != m_slotOf.end()) {
      scores.push_back(OrbVocabulary::score(bow, m_slots[it->second].bow));
    }
  }
  return scores;
}

std::vector<KeyframeDatabase::SharedWords> KeyframeDatabase::sharedWordCounts(const BowVector &bow) const
{
  std::vector<int> counts(m_slots.size(), 0);
  std::vector<SharedWords> shared;
  auto count = [&](std::uint32_t slot) {
    if (counts[slot]++ == 0) {
      shared.push_back({slot, 0});
    }
  };
  for (const BowEntry &e : bow) {
    const auto word = m_index.find(e.wordId); // absent: no keyframe holds it (or another vocabulary's word)
    if (word == m_index.end()) {
      continue;
    }
    const Word &w = word->second;
    if (w.list != kNoList) {
      for (const std::uint32_t slot : m_lists[w.list]) {
        count(slot);
      }
    }
    for (std::uint32_t h = w.chain; h != kNoHolder; h = m_holders[h].next) {
      count(m_holders[h].slot);
    }
  }
  for (SharedWords &s : shared) {
    s.count = counts[s.slot];
  }
  return shared;
}

namespace
{
using Candidate = KeyframeDatabase::Candidate;
using KeyframeId = KeyframeDatabase::KeyframeId;

/*!
  The largest count of shared words among the keyframes of \e byCount (count, keyframe) that the query does not
  exclude (0: none). Taken from a heap in decreasing count, so the exclusion rule runs on the few best keyframes, not
  on every keyframe sharing a word (a map revisited lap after lap has thousands of those: the rule on each was a
  quarter of the query's time), and the thousands are not sorted either.
*/
int largestCommonNotExcluded(std::vector<std::pair<int, KeyframeId>> byCount, const KeyframeDatabase::Query &query)
{
  std::make_heap(byCount.begin(), byCount.end());
  while (!byCount.empty()) {
    const std::pair<int, KeyframeId> best = byCount.front();
    if (!query.excluded || !query.excluded(best.second)) {
      return best.first;
    }
    std::pop_heap(byCount.begin(), byCount.end());
    byCount.pop_back();
  }
  return 0;
}

//! Groups by co-visibility: the group of a candidate is itself and its best \e groupNeighbours neighbours that are
//! candidates, represented by its best-scoring member and scored by the sum.
std::vector<Candidate> groupByCovisibility(const std::unordered_map<KeyframeId, Candidate> &scored,
                                           const KeyframeDatabase::Query &query, int groupNeighbours)
{
  std::vector<Candidate> groups;
  groups.reserve(scored.size());
  for (const auto &entry : scored) {
    Candidate best = entry.second;
    double groupScore = entry.second.score;
    if (query.covisible) {
      const std::vector<KeyframeId> neighbours = query.covisible(entry.first);
      const std::size_t count = std::min(neighbours.size(), static_cast<std::size_t>(groupNeighbours));
      for (std::size_t i = 0; i < count; ++i) {
        const auto it = scored.find(neighbours[i]);
        if (it == scored.end() || it->first == entry.first) {
          continue;
        }
        groupScore += it->second.score;
        if (it->second.score > best.score || (it->second.score == best.score && it->first < best.id)) {
          best = it->second;
        }
      }
    }
    best.groupScore = groupScore;
    groups.push_back(best);
  }
  return groups;
}

//! The groups within \e retainRatio of the best one, one entry per representative keyframe, best first.
std::vector<Candidate> retainBestGroups(std::vector<Candidate> &groups, const KeyframeDatabase::Query &query,
                                        double retainRatio)
{
  double bestGroup = 0.0;
  for (const Candidate &g : groups) {
    bestGroup = std::max(bestGroup, g.groupScore);
  }
  const double retain = retainRatio * bestGroup;
  std::sort(groups.begin(), groups.end(), [](const Candidate &a, const Candidate &b) {
    if (a.groupScore != b.groupScore) {
      return a.groupScore > b.groupScore;
    }
    if (a.score != b.score) {
      return a.score > b.score;
    }
    return a.id < b.id;
  });
  std::vector<Candidate> result;
  for (const Candidate &g : groups) {
    if (g.groupScore < retain) {
      break;
    }
    const bool seen = std::any_of(result.begin(), result.end(), [&](const Candidate &r) { return r.id == g.id; });
    if (!seen) {
      result.push_back(g);
      if (query.maxCandidates > 0 && result.size() >= query.maxCandidates) {
        break;
      }
    }
  }
  return result;
}
} // namespace

std::vector<KeyframeDatabase::Candidate> KeyframeDatabase::query(const BowVector &bow, const Query &query) const
{
  std::shared_lock<std::shared_mutex> lock(m_mutex);
  // 1. Keyframes sharing words, with the count of shared words.
  const std::vector<SharedWords> common = sharedWordCounts(bow);
  std::vector<std::pair<int, KeyframeId>> byCount;
  byCount.reserve(common.size());
  for (const SharedWords &s : common) {
    byCount.emplace_back(s.count, m_slots[s.slot].id);
  }
  const int maxCommon = largestCommonNotExcluded(std::move(byCount), query);
  if (maxCommon == 0) {
    return {};
  }

  // 2. Score the keyframes sharing enough words.
  const double minCommon = m_options.minCommonWordsRatio * maxCommon;
  std::unordered_map<KeyframeId, Candidate> scored;
  for (const SharedWords &s : common) {
    const Slot &slot = m_slots[s.slot];
    if (s.count < minCommon || (query.excluded && query.excluded(slot.id))) {
      continue;
    }
    Candidate c;
    c.id = slot.id;
    c.commonWords = s.count;
    c.score = OrbVocabulary::score(bow, slot.bow);
    c.normalizedScore = query.expectedScore > 0.0 ? c.score / query.expectedScore : c.score;
    c.groupScore = c.score;
    if (c.score >= query.minScore && c.normalizedScore >= query.minNormalizedScore) {
      scored.emplace(c.id, c);
    }
  }

  // 3. Group by co-visibility; 4. keep the groups close to the best one.
  std::vector<Candidate> groups = groupByCovisibility(scored, query, m_options.groupNeighbours);
  return retainBestGroups(groups, query, m_options.groupRetainRatio);
}

double KeyframeDatabase::memoryBytes() const
{
  std::shared_lock<std::shared_mutex> lock(m_mutex);
  return m_heapBytes + vectorHeapBytes(m_holders) + vectorHeapBytes(m_lists) + vectorHeapBytes(m_freeLists) +
         vectorHeapBytes(m_slots) + vectorHeapBytes(m_freeSlots) + hashBucketsHeapBytes(m_index) +
         hashBucketsHeapBytes(m_slotOf);
}
} // namespace hslam
