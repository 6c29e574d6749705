// Split mesh directories (`tetiso split`): an index, and a domain file and an
// edge file per domain, each ending in the xxHash digest of its bytes, the
// index listing the others' digests. A damaged byte is refused at the digest
// before any field is parsed, so the fuzzer's input is one file's contents
// without its digest, which is computed to fit (and the index's list with
// it): the first byte picks the file (0 the index, 1 domain 0, 2 the edges
// of domain 0), the rest is the file. The directory around it is a valid
// split of a small lattice cube into four domains. What loads is read whole,
// as the job's tasks read it.
#include <cstring>
#include <map>
#include <string>

#include "fuzz_support.hpp"
#include "tetiso/error.hpp"
#include "tetiso/extract.hpp"
#include "tetiso/field.hpp"
#include "tetiso/lattice.hpp"
#include "tetiso/mesh_partition.hpp"
#include "tetiso/mesh_split.hpp"

namespace {

constexpr int kDomains = 4;

std::string read_bytes(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void put_digest(std::string& bytes, std::size_t at, std::uint64_t digest) { std::memcpy(bytes.data() + at, &digest, 8); }

std::string with_digest(std::string_view content) {
    std::string bytes(content);
    const std::uint64_t digest = tetiso::split_digest(bytes.data(), bytes.size());
    bytes.append(reinterpret_cast<const char*>(&digest), 8);
    return bytes;
}

// The valid split's files, by name, written once.
const std::map<std::string, std::string>& valid_split() {
    static const std::map<std::string, std::string> files = [] {
        const tetiso::Lattice lattice(4); // Decomposition keeps a reference to it
        const tetiso::Decomposition one(lattice, 1);
        tetiso::Domain cube = one.make_domain(0, *tetiso::make_field("sphere"));
        std::vector<std::int32_t> part(cube.tet_count());
        for (std::size_t t = 0; t < part.size(); ++t) part[t] = static_cast<std::int32_t>(t * kDomains / part.size());
        const tetiso::MeshPartition partition(std::move(cube), part, "fuzz");
        const auto dir = tetiso::fuzz::scratch() / "valid";
        tetiso::write_mesh_split(partition, 2.0, dir);
        std::map<std::string, std::string> out;
        for (const auto& entry : std::filesystem::directory_iterator(dir))
            out[entry.path().filename().string()] = read_bytes(entry.path());
        // Seeds for corpus/split/: each file without its digest, after its selector byte.
        if (const char* seeds = std::getenv("TETISO_FUZZ_WRITE_SEEDS")) {
            const char* names[] = {"index.tetiso", "domain-0.tetiso", "edges-0.tetiso"};
            for (int k = 0; k < 3; ++k) {
                const std::string& file = out[names[k]];
                std::ofstream(std::filesystem::path(seeds) / (std::string("seed-") + names[k]), std::ios::binary)
                    << static_cast<char>(k) << file.substr(0, file.size() - 8);
            }
        }
        return out;
    }();
    return files;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto& valid = valid_split();
    if (size == 0) return 0;
    std::map<std::string, std::string> files = valid;
    const std::string fuzzed = with_digest(tetiso::fuzz::bytes_of(data + 1, size - 1));
    std::string& index = files["index.tetiso"];
    const std::size_t domain_digests = index.size() - 16 - 16 * kDomains, edge_digests = index.size() - 8 - 8 * kDomains;
    switch (data[0] % 3) {
    case 0: index = fuzzed; break;
    case 1:
        files["domain-0.tetiso"] = fuzzed;
        put_digest(index, domain_digests, tetiso::split_digest(fuzzed.data(), fuzzed.size() - 8));
        break;
    default:
        files["edges-0.tetiso"] = fuzzed;
        put_digest(index, edge_digests, tetiso::split_digest(fuzzed.data(), fuzzed.size() - 8));
    }
    if (data[0] % 3 != 0) index = with_digest(std::string_view(index).substr(0, index.size() - 8));
    const auto dir = tetiso::fuzz::scratch() / "split";
    std::filesystem::create_directories(dir);
    for (const auto& [name, bytes] : files) tetiso::fuzz::write_file("split/" + name, bytes);
    try {
        const tetiso::SplitMeshPartition split(dir);
        for (int d = 0; d < split.domain_count(); ++d) {
            const tetiso::Domain domain = split.make_domain(d);
            tetiso::extract(domain, static_cast<float>(split.default_level()));
            for (const tetiso::EdgeKey key : domain.shared_edges)
                split.domains_of_edge(tetiso::edge_key_low(key), tetiso::edge_key_high(key));
        }
        split.edge_domains(0, split.domain_count());
    } catch (const tetiso::Error&) {
    }
    return 0;
}
