/*
 * H-SLAM for ViSP.
 */
#include "features/VocabularyFiles.h"

#include "common/TextParsing.h"

#include <visp3/hslam/vpHSlamException.h>

#include <opencv2/core.hpp>

#include <zlib.h>

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
// DBoW2's own bounds on the text header (TemplatedVocabulary::loadFromTextFile).
constexpr int kDbow2MaxScoring = 5;
constexpr int kDbow2MaxWeighting = 3;

std::string readWholeFile(const std::string &path)
{
  requireFileExists(path, "vocabulary file");
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throwAt(vpHSlamException::fileUnreadable, path, 0, "is a folder, not a vocabulary file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throwAt(vpHSlamException::fileUnreadable, path, 0, "cannot open the vocabulary file");
  }
  // One read of the known size: several times faster than stream iterators on a 50 MB file.
  std::string bytes;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (!ec) {
    bytes.resize(static_cast<std::size_t>(size));
    in.read(&bytes[0], static_cast<std::streamsize>(size));
    bytes.resize(static_cast<std::size_t>(in.gcount()));
  }
  if (in.bad() || ec) {
    throwAt(vpHSlamException::fileUnreadable, path, 0, "read error");
  }
  if (bytes.empty()) {
    throwAt(vpHSlamException::parseError, path, 0, "empty vocabulary file");
  }
  return bytes;
}

// Little-endian encoding, independent of the host.
void putU32(std::string &out, std::uint32_t v)
{
  for (int b = 0; b < 4; ++b) {
    out.push_back(static_cast<char>((v >> (8 * b)) & 0xff));
  }
}
void putU64(std::string &out, std::uint64_t v)
{
  for (int b = 0; b < 8; ++b) {
    out.push_back(static_cast<char>((v >> (8 * b)) & 0xff));
  }
}
std::uint32_t getU32(const std::uint8_t *p)
{
  return std::uint32_t(p[0]) | (std::uint32_t(p[1]) << 8) | (std::uint32_t(p[2]) << 16) | (std::uint32_t(p[3]) << 24);
}
std::uint64_t getU64(const std::uint8_t *p)
{
  return std::uint64_t(getU32(p)) | (std::uint64_t(getU32(p + 4)) << 32);
}

//! Write bytes to a temporary file beside \e path, then rename it over \e path.
void writeAtomically(const std::string &path, const std::string &bytes)
{
  const std::string temporary = path + ".partial";
  std::ofstream out;
  openForWriting(out, temporary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  flushAndClose(out, temporary);
  std::error_code ec;
  std::filesystem::rename(temporary, path, ec);
  if (ec) {
    std::filesystem::remove(temporary, ec);
    throwAt(vpHSlamException::fileUnreadable, path, 0, "cannot write the vocabulary file (rename failed)");
  }
}

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

//! Parse "b0 b1 ... b31" (DBoW2 FORB::toString); \e what names the place for errors.
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

void assignOrThrow(OrbVocabulary &vocabulary, OrbVocabulary::Parts parts, const std::string &path)
{
  vocabulary.assign(std::move(parts), path);
}

//! Inflate a gzip stream; refuses corrupt streams and outputs over kMaxInflatedBytes (a "zip bomb").
std::string gunzip(const std::string &compressed, const std::string &path)
{
  constexpr std::size_t kMaxInflatedBytes = std::size_t(4) << 30;
  z_stream stream{};
  if (inflateInit2(&stream, 16 + MAX_WBITS) != Z_OK) {
    throwAt(vpHSlamException::fileUnreadable, path, 0, "cannot start gzip decompression");
  }
  stream.next_in = reinterpret_cast<Bytef *>(const_cast<char *>(compressed.data()));
  stream.avail_in = static_cast<uInt>(compressed.size());
  std::string out;
  char buffer[1 << 16];
  int status = Z_OK;
  while (status == Z_OK) {
    stream.next_out = reinterpret_cast<Bytef *>(buffer);
    stream.avail_out = sizeof(buffer);
    status = inflate(&stream, Z_NO_FLUSH);
    if (status != Z_OK && status != Z_STREAM_END) {
      break;
    }
    out.append(buffer, sizeof(buffer) - stream.avail_out);
    if (out.size() > kMaxInflatedBytes) {
      inflateEnd(&stream);
      throwAt(vpHSlamException::parseError, path, 0, "gzip content larger than 4 GiB");
    }
    if (status == Z_OK && stream.avail_in == 0 && stream.avail_out != 0) {
      break; // input exhausted before the end of the stream
    }
  }
  inflateEnd(&stream);
  if (status != Z_STREAM_END) {
    throwAt(vpHSlamException::parseError, path, 0, "corrupt or truncated gzip data");
  }
  return out;
}

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
  const std::string bytes = readWholeFile(path);
  const auto *p = reinterpret_cast<const std::uint8_t *>(bytes.data());
  if (bytes.size() < 8 || std::memcmp(p, kMagic, 8) != 0) {
    throwAt(vpHSlamException::parseError, path, 0, "not an H-SLAM binary vocabulary (wrong magic)");
  }
  if (bytes.size() < kHeaderBytes + kChecksumBytes) {
    throwAt(vpHSlamException::parseError, path, 0,
            "truncated: " + std::to_string(bytes.size()) + " bytes, shorter than the header");
  }
  const std::uint32_t version = getU32(p + 8);
  if (version != kBinaryVersion) {
    throwAt(vpHSlamException::unsupported, path, 0,
            "binary vocabulary format version " + std::to_string(version) + ", this build reads version " +
                std::to_string(kBinaryVersion));
  }
  const std::uint32_t descriptorBytes = getU32(p + 12);
  if (descriptorBytes != static_cast<std::uint32_t>(kOrbDescriptorBytes)) {
    throwAt(vpHSlamException::unsupported, path, 0,
            "descriptors of " + std::to_string(descriptorBytes) + " bytes, expected " +
                std::to_string(kOrbDescriptorBytes) + " (256-bit ORB)");
  }
  const std::uint32_t nodes = getU32(p + 32), words = getU32(p + 36);
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
  if (hashBytes(p, payload) != getU64(p + payload)) {
    throwAt(vpHSlamException::parseError, path, 0, "corrupt: checksum mismatch");
  }

  OrbVocabulary::Parts parts;
  parts.branching = static_cast<int>(getU32(p + 16));
  parts.levels = static_cast<int>(getU32(p + 20));
  const std::uint32_t weighting = getU32(p + 24), scoring = getU32(p + 28);
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
    parts.parents[n] = getU32(record);
    parts.descriptors[n] = descriptorFromBytes(record + 4);
  }
  parts.wordNodes.resize(words);
  parts.wordWeights.resize(words);
  for (std::uint32_t w = 0; w < words; ++w, record += kWordRecordBytes) {
    parts.wordNodes[w] = getU32(record);
    const std::uint64_t bits = getU64(record + 4);
    std::memcpy(&parts.wordWeights[w], &bits, sizeof(double));
  }
  OrbVocabulary vocabulary;
  assignOrThrow(vocabulary, std::move(parts), path);
  return vocabulary;
}

OrbVocabulary loadVocabularyDbow2Text(const std::string &path)
{
  const std::string text = readWholeFile(path);
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
  assignOrThrow(vocabulary, std::move(parts), path);
  return vocabulary;
}

namespace
{
//! Line (1-based) of a position in a text.
std::size_t lineAt(const std::string &text, std::size_t pos)
{
  return 1 + static_cast<std::size_t>(std::count(
                 text.begin(), text.begin() + static_cast<std::ptrdiff_t>(std::min(pos, text.size())), '\n'));
}

//! One flow map "{ key:value, key:"text", ... }" of DBoW2's YAML (no nesting), as key -> raw value.
std::vector<std::pair<std::string, std::string>> parseFlowMap(const std::string &body, const std::string &path,
                                                              std::size_t line)
{
  std::vector<std::pair<std::string, std::string>> fields;
  std::size_t i = 0;
  while (i < body.size()) {
    const std::size_t colon = body.find(':', i);
    if (colon == std::string::npos) {
      if (!trim(body.substr(i)).empty()) {
        throwAt(vpHSlamException::parseError, path, line, "expected 'key:value' in '{ ... }'");
      }
      break;
    }
    const std::string key = trim(body.substr(i, colon - i));
    std::size_t j = colon + 1;
    while (j < body.size() && (body[j] == ' ' || body[j] == '\t' || body[j] == '\n' || body[j] == '\r')) {
      ++j;
    }
    std::string value;
    if (j < body.size() && body[j] == '"') {
      const std::size_t close = body.find('"', j + 1);
      if (close == std::string::npos) {
        throwAt(vpHSlamException::parseError, path, line, "unterminated string in '{ ... }'");
      }
      value = body.substr(j + 1, close - j - 1);
      j = close + 1;
      const std::size_t comma = body.find(',', j);
      if (!trim(body.substr(j, comma == std::string::npos ? std::string::npos : comma - j)).empty()) {
        throwAt(vpHSlamException::parseError, path, line, "text after a string in '{ ... }'");
      }
      i = comma == std::string::npos ? body.size() : comma + 1;
    } else {
      const std::size_t comma = body.find(',', j);
      value = trim(body.substr(j, comma == std::string::npos ? std::string::npos : comma - j));
      i = comma == std::string::npos ? body.size() : comma + 1;
    }
    if (key.empty()) {
      throwAt(vpHSlamException::parseError, path, line, "empty key in '{ ... }'");
    }
    fields.emplace_back(key, value);
  }
  return fields;
}

const std::string *field(const std::vector<std::pair<std::string, std::string>> &fields, const std::string &key)
{
  for (const auto &f : fields) {
    if (f.first == key) {
      return &f.second;
    }
  }
  return nullptr;
}

//! The flow maps of a block sequence ("- { ... }" items) between two positions of the text.
std::vector<std::pair<std::size_t, std::string>> flowMaps(const std::string &text, std::size_t begin, std::size_t end,
                                                          const std::string &path)
{
  std::vector<std::pair<std::size_t, std::string>> maps;
  std::size_t i = begin;
  while (i < end) {
    const char ch = text[i];
    if (ch == '{') {
      const std::size_t close = text.find('}', i);
      if (close == std::string::npos || close > end) {
        throwAt(vpHSlamException::parseError, path, lineAt(text, i), "'{' without '}' (file cut short?)");
      }
      maps.emplace_back(lineAt(text, i), text.substr(i + 1, close - i - 1));
      i = close + 1;
    } else if (ch == '-' || ch == ' ' || ch == '\t' || ch == '\n' || ch == '\r' || ch == '[' || ch == ']') {
      ++i;
    } else {
      throwAt(vpHSlamException::parseError, path, lineAt(text, i),
              std::string("unexpected character '") + ch + "' in a list of '{ ... }' entries");
    }
  }
  return maps;
}

int intField(const std::vector<std::pair<std::string, std::string>> &fields, const std::string &key,
             const std::string &path, std::size_t line)
{
  const std::string *value = field(fields, key);
  if (!value) {
    throwAt(vpHSlamException::parseError, path, line, "missing '" + key + "'");
  }
  long long parsed = 0;
  if (!tryParseInt64(*value, parsed) || parsed < 0 || parsed > 0x7fffffffLL) {
    throwAt(vpHSlamException::parseError, path, line, "'" + key + "': '" + *value + "' is not a non-negative integer");
  }
  return static_cast<int>(parsed);
}
} // namespace

OrbVocabulary loadVocabularyDbow2Yaml(const std::string &path)
{
  // DBoW2's YAML is read by a small parser of its own layout, not by OpenCV's YAML reader, which loops for ever on
  // some malformed files (found by fuzz_vocabulary_yaml). gzip is inflated here first.
  std::string text = readWholeFile(path);
  if (text.size() >= 2 && static_cast<unsigned char>(text[0]) == 0x1f && static_cast<unsigned char>(text[1]) == 0x8b) {
    text = gunzip(text, path);
  }
  requireNoNulByte(text, path);
  // Scalars and the two lists: "key:" at the start of a (trimmed) line.
  auto keyLine = [&](const std::string &key, std::size_t from) -> std::size_t {
    std::size_t pos = from;
    while (pos < text.size()) {
      std::size_t end = text.find('\n', pos);
      if (end == std::string::npos) {
        end = text.size();
      }
      const std::string line = trim(text.substr(pos, end - pos));
      if (line.compare(0, key.size() + 1, key + ":") == 0) {
        return pos;
      }
      pos = end + 1;
    }
    return std::string::npos;
  };
  const std::size_t vocabularyAt = keyLine("vocabulary", 0);
  if (vocabularyAt == std::string::npos) {
    throwAt(vpHSlamException::parseError, path, 0, "no 'vocabulary' map (not a DBoW2 YAML vocabulary)");
  }
  auto scalar = [&](const std::string &key) {
    const std::size_t at = keyLine(key, vocabularyAt);
    if (at == std::string::npos) {
      throwAt(vpHSlamException::parseError, path, 0, "missing or non-integer '" + key + "'");
    }
    const std::size_t end = text.find('\n', at);
    const std::string line = trim(text.substr(at, end == std::string::npos ? std::string::npos : end - at));
    std::vector<std::pair<std::string, std::string>> kv = {{key, trim(line.substr(key.size() + 1))}};
    return intField(kv, key, path, lineAt(text, at));
  };
  OrbVocabulary::Parts parts;
  parts.branching = scalar("k");
  parts.levels = scalar("L");
  const int scoring = scalar("scoringType"), weighting = scalar("weightingType");
  if (scoring > kDbow2MaxScoring || weighting > kDbow2MaxWeighting) {
    throwAt(vpHSlamException::parseError, path, 0, "unknown scoring or weighting type");
  }
  parts.scoring = static_cast<VocabularyScoring>(scoring);
  parts.weighting = static_cast<VocabularyWeighting>(weighting);
  const std::size_t nodesAt = keyLine("nodes", vocabularyAt), wordsAt = keyLine("words", vocabularyAt);
  if (nodesAt == std::string::npos || wordsAt == std::string::npos || wordsAt < nodesAt) {
    throwAt(vpHSlamException::parseError, path, 0, "empty vocabulary (no 'nodes' or 'words' list)");
  }
  const std::size_t nodesBody = text.find(':', nodesAt) + 1, wordsBody = text.find(':', wordsAt) + 1;
  const auto nodeMaps = flowMaps(text, nodesBody, wordsAt, path);
  // After the words list, DBoW2 closes the vocabulary map: stop at the first line that is not part of the list.
  const auto wordMaps = flowMaps(text, wordsBody, text.size(), path);
  if (nodeMaps.empty() || wordMaps.empty()) {
    throwAt(vpHSlamException::parseError, path, 0, "empty vocabulary (no 'nodes' or 'words')");
  }
  const std::size_t nodeCount = nodeMaps.size() + 1;
  parts.parents.assign(nodeCount, 0xffffffffu);
  parts.parents[0] = 0;
  parts.descriptors.assign(nodeCount, OrbDescriptor());
  std::vector<double> nodeWeights(nodeCount, 0.0);
  for (const auto &entry : nodeMaps) {
    const auto fields = parseFlowMap(entry.second, path, entry.first);
    const int id = intField(fields, "nodeId", path, entry.first);
    const int parent = intField(fields, "parentId", path, entry.first);
    if (id <= 0 || static_cast<std::size_t>(id) >= nodeCount ||
        parts.parents[static_cast<std::size_t>(id)] != 0xffffffffu) {
      throwAt(vpHSlamException::parseError, path, entry.first,
              "node id " + std::to_string(id) + " out of [1, " + std::to_string(nodeCount - 1) + "] or repeated");
    }
    const std::string *weight = field(fields, "weight");
    const std::string *descriptor = field(fields, "descriptor");
    if (!weight || !descriptor) {
      throwAt(vpHSlamException::parseError, path, entry.first, "node without weight or descriptor");
    }
    parts.parents[static_cast<std::size_t>(id)] = static_cast<std::uint32_t>(parent);
    nodeWeights[static_cast<std::size_t>(id)] = parseDouble(*weight, path, entry.first, "node weight");
    parts.descriptors[static_cast<std::size_t>(id)] =
        descriptorFromText(*descriptor, path, entry.first, "node " + std::to_string(id));
  }
  parts.wordNodes.assign(wordMaps.size(), 0);
  std::vector<bool> seen(wordMaps.size(), false);
  for (const auto &entry : wordMaps) {
    const auto fields = parseFlowMap(entry.second, path, entry.first);
    const int word = intField(fields, "wordId", path, entry.first),
              node = intField(fields, "nodeId", path, entry.first);
    if (static_cast<std::size_t>(word) >= wordMaps.size() || seen[static_cast<std::size_t>(word)]) {
      throwAt(vpHSlamException::parseError, path, entry.first,
              "word id " + std::to_string(word) + " out of range or repeated");
    }
    if (node <= 0 || static_cast<std::size_t>(node) >= nodeCount) {
      throwAt(vpHSlamException::parseError, path, entry.first, "node id " + std::to_string(node) + " out of range");
    }
    seen[static_cast<std::size_t>(word)] = true;
    parts.wordNodes[static_cast<std::size_t>(word)] = static_cast<std::uint32_t>(node);
  }
  parts.wordWeights.resize(parts.wordNodes.size());
  for (std::size_t w = 0; w < parts.wordNodes.size(); ++w) {
    parts.wordWeights[w] = nodeWeights[parts.wordNodes[w]];
  }
  OrbVocabulary vocabulary;
  assignOrThrow(vocabulary, std::move(parts), path);
  return vocabulary;
}

void saveVocabulary(const OrbVocabulary &vocabulary, const std::string &path, VocabularyFormat format)
{
  if (vocabulary.empty()) {
    throw vpHSlamException(vpHSlamException::invalidArgument, path + ": cannot save an empty vocabulary");
  }
  const OrbVocabulary::Parts parts = vocabulary.parts();
  const std::size_t nodes = parts.parents.size(), words = parts.wordNodes.size();
  if (format == VocabularyFormat::binary || format == VocabularyFormat::automatic) {
    std::string bytes;
    bytes.reserve(kHeaderBytes + (nodes - 1) * kNodeRecordBytes + words * kWordRecordBytes + kChecksumBytes);
    bytes.append(kMagic, 8);
    putU32(bytes, kBinaryVersion);
    putU32(bytes, kOrbDescriptorBytes);
    putU32(bytes, static_cast<std::uint32_t>(parts.branching));
    putU32(bytes, static_cast<std::uint32_t>(parts.levels));
    putU32(bytes, static_cast<std::uint32_t>(parts.weighting));
    putU32(bytes, static_cast<std::uint32_t>(parts.scoring));
    putU32(bytes, static_cast<std::uint32_t>(nodes));
    putU32(bytes, static_cast<std::uint32_t>(words));
    for (std::size_t n = 1; n < nodes; ++n) {
      putU32(bytes, parts.parents[n]);
      for (int j = 0; j < kOrbDescriptorBytes; ++j) {
        bytes.push_back(static_cast<char>(parts.descriptors[n].byte(j)));
      }
    }
    for (std::size_t w = 0; w < words; ++w) {
      putU32(bytes, parts.wordNodes[w]);
      std::uint64_t bits = 0;
      std::memcpy(&bits, &parts.wordWeights[w], sizeof(double));
      putU64(bytes, bits);
    }
    putU64(bytes, hashBytes(bytes.data(), bytes.size()));
    writeAtomically(path, bytes);
    return;
  }

  std::vector<double> nodeWeights(nodes, 0.0);
  std::vector<bool> leaf(nodes, false);
  for (std::size_t w = 0; w < words; ++w) {
    nodeWeights[parts.wordNodes[w]] = parts.wordWeights[w];
    leaf[parts.wordNodes[w]] = true;
  }
  if (format == VocabularyFormat::dbow2Text) {
    // Words are numbered by leaf order when read back: identical ids when they already are (trained vocabularies).
    std::string out = std::to_string(parts.branching) + " " + std::to_string(parts.levels) + " " +
                      std::to_string(static_cast<int>(parts.scoring)) + " " +
                      std::to_string(static_cast<int>(parts.weighting)) + "\n";
    for (std::size_t n = 1; n < nodes; ++n) {
      out += std::to_string(parts.parents[n]);
      out += leaf[n] ? " 1 " : " 0 ";
      out += descriptorToText(parts.descriptors[n]);
      appendNumber(out, nodeWeights[n], std::chars_format::general, 17); // exact double round trip
      out += '\n';
    }
    writeAtomically(path, out);
    return;
  }

  // DBoW2 YAML through cv::FileStorage (gzip when the name ends with .gz), nodes breadth-first as DBoW2 writes them.
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
} // namespace hslam
