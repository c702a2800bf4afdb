// omega_protocol_examples: prints the example section of docs/protocol.md, or with
// --check FILE, fails unless FILE holds every example's hex dump exactly.
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include "protocol/tools/examples.h"

using namespace omega::protocol;

int main(int argc, char** argv) {
  auto all = examples::all();
  if (argc == 3 && std::string(argv[1]) == "--check") {
    std::ifstream in(argv[2], std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    std::string doc = ss.str();
    int missing = 0;
    for (const auto& e : all) {
      if (doc.find(examples::markdown_block(e)) == std::string::npos) {
        std::cerr << "docs out of date: example '" << e.title << "' differs\n";
        ++missing;
      }
    }
    return missing == 0 ? 0 : 1;
  }
  for (const auto& e : all) {
    Frame f = encode(e.message);
    std::cout << "#### " << e.title << "\n\nHeader: `" << f.header << "`";
    if (!f.payload.empty()) std::cout << " · payload: " << f.payload.size() << " bytes";
    std::cout << "\n\n" << examples::markdown_block(e) << "\n";
  }
  return 0;
}
