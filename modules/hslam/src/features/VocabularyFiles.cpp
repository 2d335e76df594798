/*
 * H-SLAM for ViSP.
 */
#include "features/VocabularyFiles.h"
#include "features/VocabularyFileSupport.h"

#include "common/BinaryIo.h"
#include "common/TextParsing.h"

#include <visp3/hslam/vpHSlamException.h>

#include <opencv2/core.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace hslam
{
namespace
{
const char kMagic[8] = {'H', 'S', 'L', 'A', 'M', 'V', 'O', 'C'};
constexpr std::uint32_t kBinaryVersion = 1;
constexpr std::size_t kHeaderBytes = 40;
constexpr std::size_t kNodeRecordBytes = 4 + kOrbDescriptorBytes;
constexpr std::size_t kWordRecordBytes = 4 + 8;
constexpr std::size_t kChecksumBytes = 8;
} // namespace

std::string readVocabularyFile(const std::string &path)
{
  return readBinaryFile(path, "vocabulary file");
}

namespace
{

std::string descriptorToText(const OrbDescriptor &d)
{
  std::string out;
  out.reserve(4 * kOrbDescriptorBytes);
  for (int j = 0; j < kOrbDescriptorBytes; ++j) {
    out += std::to_string(static_cast<int>(d.byte(j)));
    out += ' ';
  }
  return out;
}

} // namespace

OrbDescriptor descriptorFromText(const std::string &text, const std::string &path, std::size_t line,
                                 const std::string &what)
{
  const std::vector<std::string> tokens = splitWhitespace(text);
  if (tokens.size() != static_cast<std::size_t>(kOrbDescriptorBytes)) {
    throwAt(vpHSlamException::unsupported, path, line,
            what + ": descriptor has " + std::to_string(tokens.size()) + " bytes, expected " +
                std::to_string(kOrbDescriptorBytes) + " (256-bit ORB)");
  }
  OrbDescriptor d;
  for (int j = 0; j < kOrbDescriptorBytes; ++j) {
    const unsigned int value = parseUnsigned(tokens[static_cast<std::size_t>(j)], path, line, what + " descriptor");
    if (value > 255) {
      throwAt(vpHSlamException::parseError, path, line, what + ": descriptor byte " + std::to_string(value) + " > 255");
    }
    d.setByte(j, static_cast<std::uint8_t>(value));
  }
  return d;
}

namespace
{
//! Temporary name with the same extension (cv::FileStorage picks YAML and gzip from it).
std::string temporaryWithSameExtension(const std::string &path)
{
  const std::filesystem::path p(path);
  return (p.parent_path() / (".partial-" + p.filename().string())).string();
}
} // namespace

VocabularyFormat detectVocabularyFormat(const std::string &path)
{
  requireFileExists(path, "vocabulary file");
  std::ifstream in(path, std::ios::binary);
  char head[8] = {0};
  in.read(head, sizeof(head));
  const std::streamsize got = in.gcount();
  if (got == 8 && std::memcmp(head, kMagic, 8) == 0) {
    return VocabularyFormat::binary;
  }
  if (got >= 2 && static_cast<unsigned char>(head[0]) == 0x1f && static_cast<unsigned char>(head[1]) == 0x8b) {
    return VocabularyFormat::dbow2Yaml; // gzip: DBoW2 writes compressed YAML
  }
  if (got >= 5 && std::memcmp(head, "%YAML", 5) == 0) {
    return VocabularyFormat::dbow2Yaml;
  }
  return VocabularyFormat::dbow2Text;
}

OrbVocabulary loadVocabulary(const std::string &path, VocabularyFormat format)
{
  if (format == VocabularyFormat::automatic) {
    format = detectVocabularyFormat(path);
  }
  switch (format) {
  case VocabularyFormat::binary:
    return loadVocabularyBinary(path);
  case VocabularyFormat::dbow2Yaml:
    return loadVocabularyDbow2Yaml(path);
  default:
    return loadVocabularyDbow2Text(path);
  }
}

OrbVocabulary loadVocabularyBinary(const std::string &path)
{
  const std::string bytes = readVocabularyFile(path);
  const auto *p = reinterpret_cast<const std::uint8_t *>(bytes.data());
  if (bytes.size() < 8 || std::memcmp(p, kMagic, 8) != 0) {
    throwAt(vpHSlamException::parseError, path, 0, "not an H-SLAM binary vocabulary (wrong magic)");
  }
  if (bytes.size() < kHeaderBytes + kChecksumBytes) {
    throwAt(vpHSlamException::parseError, path, 0,
            "truncated: " + std::to_string(bytes.size()) + " bytes, shorter than the header");
  }
  const std::uint32_t version = loadU32(p + 8);
  if (version != kBinaryVersion) {
    throwAt(vpHSlamException::unsupported, path, 0,
            "binary vocabulary format version " + std::to_string(version) + ", this build reads version " +
                std::to_string(kBinaryVersion));
  }
  const std::uint32_t descriptorBytes = loadU32(p + 12);
  if (descriptorBytes != static_cast<std::uint32_t>(kOrbDescriptorBytes)) {
    throwAt(vpHSlamException::unsupported, path, 0,
            "descriptors of " + std::to_string(descriptorBytes) + " bytes, expected " +
                std::to_string(kOrbDescriptorBytes) + " (256-bit ORB)");
  }
  const std::uint32_t nodes = loadU32(p + 32), words = loadU32(p + 36);
  if (nodes < 2 || words == 0) {
    throwAt(vpHSlamException::parseError, path, 0, "empty vocabulary (no word)");
  }
  const std::uint64_t expected = kHeaderBytes + std::uint64_t(nodes - 1) * kNodeRecordBytes +
                                 std::uint64_t(words) * kWordRecordBytes + kChecksumBytes;
  if (bytes.size() < expected) {
    throwAt(vpHSlamException::parseError, path, 0,
            "truncated: " + std::to_string(bytes.size()) + " bytes, the header announces " + std::to_string(nodes) +
                " nodes and " + std::to_string(words) + " words (" + std::to_string(expected) + " bytes)");
  }
  if (bytes.size() > expected) {
    throwAt(vpHSlamException::parseError, path, 0,
            std::to_string(bytes.size() - expected) + " unexpected bytes after the checksum");
  }
  const std::size_t payload = static_cast<std::size_t>(expected - kChecksumBytes);
  if (hashBytes(p, payload) != loadU64(p + payload)) {
    throwAt(vpHSlamException::parseError, path, 0, "corrupt: checksum mismatch");
  }

  OrbVocabulary::Parts parts;
  parts.branching = static_cast<int>(loadU32(p + 16));
  parts.levels = static_cast<int>(loadU32(p + 20));
  const std::uint32_t weighting = loadU32(p + 24), scoring = loadU32(p + 28);
  if (weighting > static_cast<std::uint32_t>(kDbow2MaxWeighting) ||
      scoring > static_cast<std::uint32_t>(kDbow2MaxScoring)) {
    throwAt(vpHSlamException::parseError, path, 0, "unknown weighting or scoring type");
  }
  parts.weighting = static_cast<VocabularyWeighting>(weighting);
  parts.scoring = static_cast<VocabularyScoring>(scoring);
  parts.parents.resize(nodes);
  parts.descriptors.resize(nodes);
  const std::uint8_t *record = p + kHeaderBytes;
  for (std::uint32_t n = 1; n < nodes; ++n, record += kNodeRecordBytes) {
    parts.parents[n] = loadU32(record);
    parts.descriptors[n] = descriptorFromBytes(record + 4);
  }
  parts.wordNodes.resize(words);
  parts.wordWeights.resize(words);
  for (std::uint32_t w = 0; w < words; ++w, record += kWordRecordBytes) {
    parts.wordNodes[w] = loadU32(record);
    const std::uint64_t bits = loadU64(record + 4);
    std::memcpy(&parts.wordWeights[w], &bits, sizeof(double));
  }
  OrbVocabulary vocabulary;
  vocabulary.assign(std::move(parts), path);
  return vocabulary;
}

OrbVocabulary loadVocabularyDbow2Text(const std::string &path)
{
  const std::string text = readVocabularyFile(path);
  OrbVocabulary::Parts parts;
  parts.parents.assign(1, 0);
  parts.descriptors.assign(1, OrbDescriptor());
  std::size_t lineNumber = 0;
  std::size_t pos = 0;
  bool headerRead = false;
  std::vector<std::string> tokens;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) {
      end = text.size();
    }
    ++lineNumber;
    tokens = splitWhitespace(text.substr(pos, end - pos));
    pos = end + 1;
    if (tokens.empty()) {
      continue; // blank lines (ORB-SLAM2's files end with one)
    }
    if (!headerRead) {
      if (tokens.size() != 4) {
        throwAt(vpHSlamException::parseError, path, lineNumber,
                "not a DBoW2 text vocabulary: the first line must be 'k L scoring weighting', found " +
                    std::to_string(tokens.size()) + " values");
      }
      parts.branching = static_cast<int>(parseUnsigned(tokens[0], path, lineNumber, "branching factor k"));
      parts.levels = static_cast<int>(parseUnsigned(tokens[1], path, lineNumber, "depth L"));
      const unsigned int scoring = parseUnsigned(tokens[2], path, lineNumber, "scoring type");
      const unsigned int weighting = parseUnsigned(tokens[3], path, lineNumber, "weighting type");
      if (scoring > static_cast<unsigned int>(kDbow2MaxScoring) ||
          weighting > static_cast<unsigned int>(kDbow2MaxWeighting)) {
        throwAt(vpHSlamException::parseError, path, lineNumber, "unknown scoring or weighting type");
      }
      parts.scoring = static_cast<VocabularyScoring>(scoring);
      parts.weighting = static_cast<VocabularyWeighting>(weighting);
      headerRead = true;
      continue;
    }
    const std::size_t expectedFields = 3 + kOrbDescriptorBytes;
    if (tokens.size() != expectedFields) {
      if (tokens.size() > 3) {
        throwAt(vpHSlamException::unsupported, path, lineNumber,
                "node descriptor has " + std::to_string(tokens.size() - 3) + " bytes, expected " +
                    std::to_string(kOrbDescriptorBytes) + " (256-bit ORB)");
      }
      throwAt(vpHSlamException::parseError, path, lineNumber,
              "expected 'parent isLeaf' + 32 descriptor bytes + weight, found " + std::to_string(tokens.size()) +
                  " values (file cut short?)");
    }
    const std::uint32_t node = static_cast<std::uint32_t>(parts.parents.size());
    parts.parents.push_back(parseUnsigned(tokens[0], path, lineNumber, "parent node"));
    const unsigned int isLeaf = parseUnsigned(tokens[1], path, lineNumber, "leaf flag");
    OrbDescriptor d;
    for (int j = 0; j < kOrbDescriptorBytes; ++j) {
      const unsigned int value = parseUnsigned(tokens[2 + static_cast<std::size_t>(j)], path, lineNumber, "descriptor");
      if (value > 255) {
        throwAt(vpHSlamException::parseError, path, lineNumber, "descriptor byte " + std::to_string(value) + " > 255");
      }
      d.setByte(j, static_cast<std::uint8_t>(value));
    }
    parts.descriptors.push_back(d);
    const double weight = parseDouble(tokens.back(), path, lineNumber, "node weight");
    if (isLeaf > 0) {
      parts.wordNodes.push_back(node);
      parts.wordWeights.push_back(weight);
    }
  }
  if (!headerRead) {
    throwAt(vpHSlamException::parseError, path, 0, "empty vocabulary file");
  }
  OrbVocabulary vocabulary;
  vocabulary.assign(std::move(parts), path);
  return vocabulary;
}

namespace
{
//! Our binary format: header, node records (parent, descriptor), word records (node, weight), checksum.
void saveBinary(const OrbVocabulary::Parts &parts, const std::string &path)
{
  const std::size_t nodes = parts.parents.size(), words = parts.wordNodes.size();
  ByteWriter writer;
  std::string &bytes = writer.bytes();
  bytes.reserve(kHeaderBytes + (nodes - 1) * kNodeRecordBytes + words * kWordRecordBytes + kChecksumBytes);
  bytes.append(kMagic, 8);
  writer.u32(kBinaryVersion);
  writer.u32(kOrbDescriptorBytes);
  writer.u32(static_cast<std::uint32_t>(parts.branching));
  writer.u32(static_cast<std::uint32_t>(parts.levels));
  writer.u32(static_cast<std::uint32_t>(parts.weighting));
  writer.u32(static_cast<std::uint32_t>(parts.scoring));
  writer.u32(static_cast<std::uint32_t>(nodes));
  writer.u32(static_cast<std::uint32_t>(words));
  for (std::size_t n = 1; n < nodes; ++n) {
    writer.u32(parts.parents[n]);
    for (int j = 0; j < kOrbDescriptorBytes; ++j) {
      bytes.push_back(static_cast<char>(parts.descriptors[n].byte(j)));
    }
  }
  for (std::size_t w = 0; w < words; ++w) {
    writer.u32(parts.wordNodes[w]);
    std::uint64_t bits = 0;
    std::memcpy(&bits, &parts.wordWeights[w], sizeof(double));
    writer.u64(bits);
  }
  writer.u64(hashBytes(bytes.data(), bytes.size()));
  writeFileAtomically(path, bytes, "vocabulary file");
}

//! DBoW2's text format: one line per node (parent, leaf flag, descriptor, weight) after the parameters line.
void saveDbow2Text(const OrbVocabulary::Parts &parts, const std::vector<double> &nodeWeights,
                   const std::vector<bool> &leaf, const std::string &path)
{
  // Words are numbered by leaf order when read back: identical ids when they already are (trained vocabularies).
  std::string out = std::to_string(parts.branching) + " " + std::to_string(parts.levels) + " " +
                    std::to_string(static_cast<int>(parts.scoring)) + " " +
                    std::to_string(static_cast<int>(parts.weighting)) + "\n";
  for (std::size_t n = 1; n < parts.parents.size(); ++n) {
    out += std::to_string(parts.parents[n]);
    out += leaf[n] ? " 1 " : " 0 ";
    out += descriptorToText(parts.descriptors[n]);
    appendNumber(out, nodeWeights[n], std::chars_format::general, 17); // exact double round trip
    out += '\n';
  }
  writeFileAtomically(path, out, "vocabulary file");
}

//! DBoW2 YAML through cv::FileStorage (gzip when the name ends with .gz), nodes breadth-first as DBoW2 writes them;
//! written to a temporary file renamed at the end.
void saveDbow2Yaml(const OrbVocabulary::Parts &parts, const std::vector<double> &nodeWeights, const std::string &path)
{
  const std::size_t nodes = parts.parents.size(), words = parts.wordNodes.size();
  const std::string temporary = temporaryWithSameExtension(path);
  try {
    cv::FileStorage fs(temporary, cv::FileStorage::WRITE);
    if (!fs.isOpened()) {
      throwAt(vpHSlamException::fileUnreadable, path, 0, "cannot write the vocabulary file");
    }
    fs << "vocabulary"
       << "{";
    fs << "k" << parts.branching << "L" << parts.levels << "scoringType" << static_cast<int>(parts.scoring)
       << "weightingType" << static_cast<int>(parts.weighting);
    fs << "nodes"
       << "[";
    for (std::size_t n = 1; n < nodes; ++n) {
      fs << "{:"
         << "nodeId" << static_cast<int>(n) << "parentId" << static_cast<int>(parts.parents[n]) << "weight"
         << nodeWeights[n] << "descriptor" << descriptorToText(parts.descriptors[n]) << "}";
    }
    fs << "]";
    fs << "words"
       << "[";
    for (std::size_t w = 0; w < words; ++w) {
      fs << "{:"
         << "wordId" << static_cast<int>(w) << "nodeId" << static_cast<int>(parts.wordNodes[w]) << "}";
    }
    fs << "]"
       << "}";
    fs.release();
  } catch (const cv::Exception &e) {
    std::error_code ec;
    std::filesystem::remove(temporary, ec);
    throwAt(vpHSlamException::fileUnreadable, path, 0, std::string("cannot write the vocabulary file: ") + e.what());
  }
  std::error_code ec;
  std::filesystem::rename(temporary, path, ec);
  if (ec) {
    std::filesystem::remove(temporary, ec);
    throwAt(vpHSlamException::fileUnreadable, path, 0, "cannot write the vocabulary file (rename failed)");
  }
}
} // namespace

void saveVocabulary(const OrbVocabulary &vocabulary, const std::string &path, VocabularyFormat format)
{
  if (vocabulary.empty()) {
    throw vpHSlamException(vpHSlamException::invalidArgument, path + ": cannot save an empty vocabulary");
  }
  const OrbVocabulary::Parts parts = vocabulary.parts();
  if (format == VocabularyFormat::binary || format == VocabularyFormat::automatic) {
    saveBinary(parts, path);
    return;
  }
  // The text formats give each node its weight (0 for inner nodes) and leaf flag.
  const std::size_t nodes = parts.parents.size(), words = parts.wordNodes.size();
  std::vector<double> nodeWeights(nodes, 0.0);
  std::vector<bool> leaf(nodes, false);
  for (std::size_t w = 0; w < words; ++w) {
    nodeWeights[parts.wordNodes[w]] = parts.wordWeights[w];
    leaf[parts.wordNodes[w]] = true;
  }
  if (format == VocabularyFormat::dbow2Text) {
    saveDbow2Text(parts, nodeWeights, leaf, path);
  } else {
    saveDbow2Yaml(parts, nodeWeights, path);
  }
}
} // namespace hslam
