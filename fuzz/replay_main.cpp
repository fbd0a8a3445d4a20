// dsreg — runs fuzz targets on files: the committed regression corpus (a normal CTest test, any
// compiler), the generated seed corpus, or one input to see what a reader says about it.
//
//   dsreg_fuzz_replay CORPUS_ROOT                   every file of CORPUS_ROOT/<target>/ through <target>
//   dsreg_fuzz_replay --expect-accepted CORPUS_ROOT  same, and each input must be accepted (seeds)
//   dsreg_fuzz_replay --expect-messages FILE CORPUS_ROOT
//                                                   same, and FILE lists "target/name<TAB>text": that input
//                                                   must be rejected with a message containing text
//   dsreg_fuzz_replay --explain TARGET FILE...      prints "accepted" or the message, for each FILE
//
// A broken promise aborts (exit by SIGABRT); any other failure exits 1.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include "fuzz_targets.hpp"

namespace fs = std::filesystem;
using dsreg::fuzz::Outcome;

namespace {

std::vector<std::uint8_t> read_bytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("cannot read " + path.string());
    return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

Outcome run(const dsreg::fuzz::Target& target, const fs::path& path) {
    const std::vector<std::uint8_t> bytes = read_bytes(path);
    return target.run(bytes.data(), bytes.size());
}

/// "target/name" -> expected message fragment.
std::map<std::string, std::string> read_expectations(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw std::runtime_error("cannot read " + path);
    std::map<std::string, std::string> expected;
    std::string line;
    while (std::getline(in, line)) {
        if (line.empty() || line[0] == '#') continue;
        const auto tab = line.find('\t');
        if (tab == std::string::npos) throw std::runtime_error(path + ": line without a tab: " + line);
        expected[line.substr(0, tab)] = line.substr(tab + 1);
    }
    return expected;
}

int replay(const fs::path& root, bool expect_accepted, std::map<std::string, std::string> expected) {
    int failures = 0, inputs = 0;
    for (const auto& target : dsreg::fuzz::targets()) {
        const fs::path folder = root / target.name;
        if (!fs::is_directory(folder)) continue;
        std::vector<fs::path> files;
        for (const auto& entry : fs::directory_iterator(folder))
            if (entry.is_regular_file()) files.push_back(entry.path());
        std::sort(files.begin(), files.end());
        int accepted = 0;
        for (const fs::path& file : files) {
            const Outcome outcome = run(target, file);
            ++inputs;
            accepted += outcome.accepted ? 1 : 0;
            const std::string key = std::string(target.name) + "/" + file.filename().string();
            if (expect_accepted && !outcome.accepted) {
                std::cerr << "FAIL " << key << ": rejected: " << outcome.message << "\n";
                ++failures;
            }
            const auto found = expected.find(key);
            if (found != expected.end()) {
                if (outcome.accepted || outcome.message.find(found->second) == std::string::npos) {
                    std::cerr << "FAIL " << key << ": expected a message containing '" << found->second << "', got "
                              << (outcome.accepted ? "accepted" : "'" + outcome.message + "'") << "\n";
                    ++failures;
                }
                expected.erase(found);
            }
        }
        std::cout << target.name << ": " << files.size() << " inputs, " << accepted << " accepted\n";
    }
    for (const auto& [key, text] : expected) {
        std::cerr << "FAIL " << key << ": listed in the expectations but not found\n";
        ++failures;
    }
    std::cout << inputs << " inputs replayed, " << failures << " failures\n";
    return failures == 0 && inputs > 0 ? 0 : 1;
}

int usage() {
    std::cerr << "usage: dsreg_fuzz_replay [--expect-accepted | --expect-messages FILE] CORPUS_ROOT\n"
                 "       dsreg_fuzz_replay --explain TARGET FILE...\n";
    return 2;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        const std::vector<std::string> args(argv + 1, argv + argc);
        if (args.size() >= 3 && args[0] == "--explain") {
            const auto* target = dsreg::fuzz::find_target(args[1]);
            if (target == nullptr) return usage();
            for (std::size_t i = 2; i < args.size(); ++i) {
                const Outcome outcome = run(*target, args[i]);
                std::cout << args[i] << "\t" << (outcome.accepted ? "accepted" : outcome.message) << "\n";
            }
            return 0;
        }
        if (args.size() == 1) return replay(args[0], false, {});
        if (args.size() == 2 && args[0] == "--expect-accepted") return replay(args[1], true, {});
        if (args.size() == 3 && args[0] == "--expect-messages") return replay(args[2], false, read_expectations(args[1]));
        return usage();
    } catch (const std::exception& error) {
        std::cerr << "dsreg_fuzz_replay: " << error.what() << "\n";
        return 1;
    }
}
