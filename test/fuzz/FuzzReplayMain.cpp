// Replay driver of the fuzz targets for builds without libFuzzer (any compiler): runs LLVMFuzzerTestOneInput once
// on every file given on the command line, folders searched recursively (the seed corpus and the regression inputs
// of past findings). A parser crash, an escaping exception or a sanitizer report fails the run.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

namespace
{
void replay(const std::filesystem::path &file, std::size_t &count)
{
  std::ifstream in(file, std::ios::binary);
  const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  LLVMFuzzerTestOneInput(reinterpret_cast<const uint8_t *>(bytes.data()), bytes.size());
  ++count;
}
} // namespace

int main(int argc, char *argv[])
{
  std::size_t count = 0;
  for (int i = 1; i < argc; ++i) {
    const std::filesystem::path path(argv[i]);
    if (std::filesystem::is_directory(path)) {
      for (const auto &entry : std::filesystem::recursive_directory_iterator(path)) {
        if (entry.is_regular_file()) {
          replay(entry.path(), count);
        }
      }
    } else if (std::filesystem::is_regular_file(path)) {
      replay(path, count);
    } else {
      std::cerr << "no such input: " << path << std::endl;
      return 1;
    }
  }
  std::cout << "replayed " << count << " inputs" << std::endl; // 0 when the shared data is absent
  return 0;
}
