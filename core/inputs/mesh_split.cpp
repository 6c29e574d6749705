// A mesh stored as one file per domain (see mesh_split.hpp): writing a
// MeshPartition out, and the partition that reads it back piecewise.
#include "tetiso/mesh_split.hpp"

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <tuple>
#include <type_traits>
#include <utility>

#include "byte_buffer.hpp"
#include "io_formats.hpp"
#include "tetiso/detail/write_atomically.hpp"
#include "tetiso/error.hpp"
#include "tetiso/io.hpp"

#define XXH_INLINE_ALL
#include <xxhash.h>

namespace tetiso {
namespace {

static_assert(std::endian::native == std::endian::little, "split files are little-endian, as is this machine's memory");

// Eight bytes each: which kind of file, and the format's version (bumped
// whenever the layout changes, so that an old file is refused by name).
constexpr char kIndexMagic[8] = {'T', 'E', 'T', 'I', 'S', 'O', 'I', 'X'};
constexpr char kDomainMagic[8] = {'T', 'E', 'T', 'I', 'S', 'O', 'D', 'M'};
constexpr char kEdgesMagic[8] = {'T', 'E', 'T', 'I', 'S', 'O', 'E', 'D'};
constexpr std::uint32_t kVersion = 1;

// A file's bytes built up in memory, then written whole with the digest of
// everything before it at the end.
class ByteWriter : public detail::ByteWriter<std::string> {
public:
    void put_string(const std::string& text) {
        put(static_cast<std::uint64_t>(text.size()));
        bytes.append(text);
    }
    // The digest written last, which the index keeps for a domain file.
    std::uint64_t write(const std::filesystem::path& path) {
        const std::uint64_t digest = split_digest(bytes.data(), bytes.size());
        put(digest);
        std::ofstream out(path, std::ios::binary | std::ios::trunc);
        out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
        out.close();
        if (!out) throw Error(path.string() + ": cannot write: " + std::strerror(errno));
        return digest;
    }
};

// Reads back what ByteWriter wrote: the magic, the digest of the whole, the
// format version, then the fields between (byte_buffer.hpp checks each
// count against the bytes left).
class ByteReader {
public:
    ByteReader(std::filesystem::path path, const char (&magic)[8], const char* what)
        : path_(std::move(path)), bytes_(detail::read_whole_file(path_)) {
        if (bytes_.size() < sizeof(magic) + sizeof(std::uint32_t) + sizeof(std::uint64_t) ||
            std::memcmp(bytes_.data(), magic, sizeof(magic)) != 0)
            fail(std::string("not a tetiso ") + what + " file");
        const std::size_t end = bytes_.size() - sizeof(std::uint64_t);
        std::memcpy(&digest_, bytes_.data() + end, sizeof(digest_));
        if (split_digest(bytes_.data(), end) != digest_)
            fail("damaged: its contents do not match its digest");
        fields_ = detail::ByteReader(std::string_view(bytes_).substr(sizeof(magic), end - sizeof(magic)),
                                     [this](const char* name) { fail(std::string("truncated in ") + name); });
        if (const auto version = get<std::uint32_t>(); version != kVersion)
            fail("format version " + std::to_string(version) + ", where this tetiso reads version " +
                 std::to_string(kVersion));
    }
    ByteReader(const ByteReader&) = delete; // the check's `this` is this object's
    ByteReader& operator=(const ByteReader&) = delete;

    template <class T>
    T get() {
        return fields_.get<T>();
    }
    template <class T>
    std::vector<T> get_array(const char* name) {
        return fields_.get_array<T>(name);
    }
    std::string get_string(const char* name) {
        const auto size = get<std::uint64_t>();
        return std::string(fields_.get_bytes(static_cast<std::size_t>(size), name));
    }
    // Called after the last field: trailing bytes mean a layout this reader
    // does not know.
    void finish() {
        if (fields_.left() != 0) fail(std::to_string(fields_.left()) + " bytes after the last field");
        std::string().swap(bytes_); // nothing is read after the last field
    }
    std::uint64_t digest() const { return digest_; }
    [[noreturn]] void fail(const std::string& what) const { throw Error(path_.string() + ": " + what); }

private:
    std::filesystem::path path_;
    std::string bytes_;
    detail::ByteReader fields_{{}, nullptr};
    std::uint64_t digest_ = 0;
};

// Offsets into a list of rows: first[0] = 0, non-decreasing, last = size.
bool valid_offsets(const std::vector<std::int64_t>& first, std::size_t rows, std::size_t size) {
    if (first.size() != rows + 1 || first.front() != 0 || static_cast<std::size_t>(first.back()) != size) return false;
    return std::is_sorted(first.begin(), first.end());
}

} // namespace

std::uint64_t split_digest(const void* data, std::size_t size) { return XXH3_64bits(data, size); }

std::filesystem::path split_index_file(const std::filesystem::path& dir) { return dir / "index.tetiso"; }

std::filesystem::path split_edges_file(const std::filesystem::path& dir, int domain) {
    return dir / ("edges-" + std::to_string(domain) + ".tetiso");
}

std::filesystem::path split_domain_file(const std::filesystem::path& dir, int domain) {
    return dir / ("domain-" + std::to_string(domain) + ".tetiso");
}

void require_new_split_directory(const std::filesystem::path& dir) {
    std::error_code ec;
    if (std::filesystem::exists(dir, ec) &&
        (!std::filesystem::is_directory(dir, ec) || !std::filesystem::is_empty(dir, ec)))
        throw Error(dir.string() + ": exists and is not an empty directory; a split is written only to a new one");
}

void write_mesh_split(const Partition& partition, double default_level, const std::filesystem::path& dir) {
    require_new_split_directory(dir);
    // Written into a new directory beside the target and renamed into
    // place: a failed split leaves nothing behind.
    write_atomically(
        dir,
        [&](const std::filesystem::path& temporary) {
        const int domains = partition.domain_count();
        std::vector<std::uint64_t> domain_digests(static_cast<std::size_t>(domains)), edge_digests(domain_digests);
        std::vector<std::string> names(static_cast<std::size_t>(domains));
        for (int d = 0; d < domains; ++d) {
            const Domain domain = partition.make_domain(d);
            ByteWriter out;
            out.put(kDomainMagic);
            out.put(kVersion);
            out.put(static_cast<std::int32_t>(d));
            out.put_array(domain.x);
            out.put_array(domain.y);
            out.put_array(domain.z);
            out.put_array(domain.f);
            out.put_array(domain.gid);
            out.put_array(domain.interface);
            out.put_array(domain.shared_edges);
            out.put_array(domain.tets);
            domain_digests[static_cast<std::size_t>(d)] = out.write(split_domain_file(temporary, d));
            // The domain's shared edges again, each with its holders: a seam
            // reads these small files, never the tetrahedra.
            std::vector<std::int64_t> first{0};
            std::vector<std::int32_t> holders;
            for (const EdgeKey key : domain.shared_edges) {
                for (const int h : partition.domains_of_edge(edge_key_low(key), edge_key_high(key))) holders.push_back(h);
                first.push_back(static_cast<std::int64_t>(holders.size()));
            }
            ByteWriter edges;
            edges.put(kEdgesMagic);
            edges.put(kVersion);
            edges.put(static_cast<std::int32_t>(d));
            edges.put_array(domain.shared_edges);
            edges.put_array(first);
            edges.put_array(holders);
            edge_digests[static_cast<std::size_t>(d)] = edges.write(split_edges_file(temporary, d));
            names[static_cast<std::size_t>(d)] = partition.domain_name(d);
        }
        ByteWriter index;
        index.put(kIndexMagic);
        index.put(kVersion);
        index.put(static_cast<std::int32_t>(domains));
        index.put(partition.node_count());
        index.put(partition.tet_count());
        index.put(partition.spacing());
        index.put(default_level);
        index.put(partition.fingerprint());
        index.put_array(partition.tree());
        std::vector<std::int64_t> neighbour_first{0};
        std::vector<std::int32_t> neighbour_list;
        for (int d = 0; d < domains; ++d) {
            for (const int n : partition.neighbours(d)) neighbour_list.push_back(n);
            neighbour_first.push_back(static_cast<std::int64_t>(neighbour_list.size()));
        }
        index.put_array(neighbour_first);
        index.put_array(neighbour_list);
        for (const std::string& name : names) index.put_string(name);
        index.put_array(domain_digests);
        index.put_array(edge_digests);
        index.write(split_index_file(temporary));
        },
        /*directory=*/true);
}

SplitMeshPartition::SplitMeshPartition(std::filesystem::path dir) : dir_(std::move(dir)) {
    ByteReader in(split_index_file(dir_), kIndexMagic, "split index");
    const auto domains = in.get<std::int32_t>();
    if (domains < 1) in.fail("domain count " + std::to_string(domains) + " is not positive");
    const auto d_count = static_cast<std::size_t>(domains);
    node_count_ = in.get<std::int64_t>();
    tet_count_ = in.get<std::int64_t>();
    spacing_ = in.get<double>();
    default_level_ = in.get<double>();
    fingerprint_ = in.get<std::uint64_t>();
    if (node_count_ < 0 || tet_count_ < 0) in.fail("negative node or tetrahedron count");
    if (!(spacing_ >= 0) || !std::isfinite(spacing_) || !std::isfinite(default_level_))
        in.fail("spacing or level is not a finite number");
    tree_ = in.get_array<DomainTreeNode>("the merge tree");
    // A tree over D leaves has 2D - 1 nodes; each covers a range of domains,
    // and an inner node's children come after it and cover its two halves.
    if (tree_.size() != 2 * d_count - 1) in.fail("a merge tree of " + std::to_string(tree_.size()) + " nodes for " + std::to_string(domains) + " domains");
    for (std::size_t i = 0; i < tree_.size(); ++i) {
        const DomainTreeNode& n = tree_[i];
        const bool leaf = n.left < 0 && n.right < 0;
        const bool range_ok = n.first >= 0 && n.count >= 1 && n.first <= domains - n.count;
        const auto child = [&](int c) { return c > static_cast<int>(i) && c < static_cast<int>(tree_.size()); };
        bool ok = range_ok && (leaf ? n.count == 1 : child(n.left) && child(n.right));
        if (ok && !leaf) {
            const DomainTreeNode &l = tree_[static_cast<std::size_t>(n.left)], &r = tree_[static_cast<std::size_t>(n.right)];
            // The children are checked in their own turn, later: their sums
            // here may not fit an int.
            ok = l.first == n.first && std::int64_t{r.first} == std::int64_t{l.first} + l.count &&
                 std::int64_t{l.count} + r.count == n.count;
        }
        if (!ok) in.fail("merge tree node " + std::to_string(i) + " is malformed");
    }
    if (tree_.front().first != 0 || tree_.front().count != domains) in.fail("the merge tree's root does not cover every domain");
    // Every node but the root the child of exactly one: a tree, not a graph
    // that reaches a subtree twice.
    std::vector<int> parents(tree_.size(), 0);
    for (const DomainTreeNode& n : tree_)
        if (n.left >= 0) ++parents[static_cast<std::size_t>(n.left)], ++parents[static_cast<std::size_t>(n.right)];
    for (std::size_t i = 1; i < tree_.size(); ++i)
        if (parents[i] != 1) in.fail("merge tree node " + std::to_string(i) + " has " + std::to_string(parents[i]) + " parents");
    const auto neighbour_first = in.get_array<std::int64_t>("the neighbours");
    const auto neighbour_list = in.get_array<std::int32_t>("the neighbours");
    if (!valid_offsets(neighbour_first, d_count, neighbour_list.size())) in.fail("the neighbour lists are malformed");
    neighbours_.resize(d_count);
    for (std::size_t d = 0; d < d_count; ++d) {
        neighbours_[d].assign(neighbour_list.begin() + neighbour_first[d], neighbour_list.begin() + neighbour_first[d + 1]);
        for (const int n : neighbours_[d])
            if (n < 0 || n >= domains || n == static_cast<int>(d)) in.fail("domain " + std::to_string(d) + " has neighbour " + std::to_string(n));
        if (!std::is_sorted(neighbours_[d].begin(), neighbours_[d].end())) in.fail("domain " + std::to_string(d) + "'s neighbours are not sorted");
    }
    names_.resize(d_count);
    for (std::string& name : names_) name = in.get_string("the domain names");
    domain_digests_ = in.get_array<std::uint64_t>("the domain digests");
    edge_digests_ = in.get_array<std::uint64_t>("the edge digests");
    if (domain_digests_.size() != d_count || edge_digests_.size() != d_count)
        in.fail("digests for " + std::to_string(domain_digests_.size()) + " and " + std::to_string(edge_digests_.size()) +
                " domains, where it has " + std::to_string(domains));
    in.finish();
}

namespace {

// Shared edges with their domains, sorted by key, each once.
struct EdgeTable {
    std::vector<EdgeKey> keys;
    std::vector<std::int64_t> first;
    std::vector<std::int32_t> holders;

    std::vector<int> find(GlobalId a, GlobalId b) const {
        if (a < 0 || b < 0 || a > kMaxGlobalId || b > kMaxGlobalId) return {};
        const EdgeKey key = edge_key(a, b);
        const auto found = std::lower_bound(keys.begin(), keys.end(), key);
        if (found == keys.end() || *found != key) return {};
        const auto e = static_cast<std::size_t>(found - keys.begin());
        return {holders.begin() + first[e], holders.begin() + first[e + 1]};
    }
};

} // namespace

EdgeDomains SplitMeshPartition::edge_domains(int first, int count) const {
    if (first < 0 || count < 1 || first > domain_count() - count)
        throw Error("no domains " + std::to_string(first) + " to " + std::to_string(first + count - 1) + " in the split " +
                    dir_.string() + " of " + std::to_string(domain_count()));
    // (key, holders) of every domain in the range; an edge two of them share
    // comes twice, with the same holders.
    std::vector<std::tuple<EdgeKey, int, std::int64_t, std::int64_t>> rows; // key, domain, holder range
    std::vector<std::vector<std::int32_t>> holders_of(static_cast<std::size_t>(count));
    for (int d = first; d < first + count; ++d) {
        ByteReader in(split_edges_file(dir_, d), kEdgesMagic, "split edges");
        if (in.digest() != edge_digests_[static_cast<std::size_t>(d)])
            in.fail("not the file that " + split_index_file(dir_).string() + " lists for domain " + std::to_string(d) +
                    " (from another split?)");
        if (const auto id = in.get<std::int32_t>(); id != d) in.fail("holds the edges of domain " + std::to_string(id));
        const auto keys = in.get_array<EdgeKey>("the shared edges");
        const auto row_first = in.get_array<std::int64_t>("the shared edges");
        auto holders = in.get_array<std::int32_t>("the shared edges");
        in.finish();
        if (!valid_offsets(row_first, keys.size(), holders.size()) ||
            std::adjacent_find(keys.begin(), keys.end(), std::greater_equal<>()) != keys.end())
            in.fail("its shared edges are malformed");
        for (std::size_t e = 0; e < keys.size(); ++e) {
            const auto begin = holders.begin() + row_first[e], end = holders.begin() + row_first[e + 1];
            if (end - begin < 2 || !std::is_sorted(begin, end) || *begin < 0 || *(end - 1) >= domain_count() ||
                !std::binary_search(begin, end, d))
                in.fail("shared edge " + std::to_string(e) + " does not list two or more domains in range, this one among them");
            rows.emplace_back(keys[e], d - first, row_first[e], row_first[e + 1]);
        }
        holders_of[static_cast<std::size_t>(d - first)] = std::move(holders);
    }
    std::sort(rows.begin(), rows.end());
    auto table = std::make_shared<EdgeTable>();
    table->first.push_back(0);
    for (std::size_t i = 0; i < rows.size(); ++i) {
        const auto& [key, slot, begin, end] = rows[i];
        if (i > 0 && std::get<0>(rows[i - 1]) == key) continue;
        const auto& list = holders_of[static_cast<std::size_t>(slot)];
        table->keys.push_back(key);
        table->holders.insert(table->holders.end(), list.begin() + begin, list.begin() + end);
        table->first.push_back(static_cast<std::int64_t>(table->holders.size()));
    }
    return [table](GlobalId a, GlobalId b) { return table->find(a, b); };
}

std::vector<int> SplitMeshPartition::domains_of_edge(GlobalId a, GlobalId b) const {
    std::call_once(all_edges_once_, [this] { all_edges_ = edge_domains(0, domain_count()); });
    return all_edges_(a, b);
}

std::string SplitMeshPartition::domain_name(int domain) const { return names_.at(static_cast<std::size_t>(domain)); }

Domain SplitMeshPartition::make_domain(int domain) const {
    if (domain < 0 || domain >= domain_count())
        throw Error("no domain " + std::to_string(domain) + " in the split " + dir_.string() + " of " +
                    std::to_string(domain_count()));
    ByteReader in(split_domain_file(dir_, domain), kDomainMagic, "split domain");
    if (in.digest() != domain_digests_[static_cast<std::size_t>(domain)])
        in.fail("not the file that " + split_index_file(dir_).string() + " lists for domain " + std::to_string(domain) +
                " (from another split?)");
    if (const auto id = in.get<std::int32_t>(); id != domain) in.fail("holds domain " + std::to_string(id));
    Domain out;
    out.id = domain;
    out.x = in.get_array<float>("the positions");
    out.y = in.get_array<float>("the positions");
    out.z = in.get_array<float>("the positions");
    out.f = in.get_array<float>("the field values");
    out.gid = in.get_array<GlobalId>("the global ids");
    out.interface = in.get_array<std::uint8_t>("the interface marks");
    out.shared_edges = in.get_array<EdgeKey>("the shared edges");
    out.tets = in.get_array<std::int32_t>("the tetrahedra");
    in.finish();
    const std::size_t n = out.gid.size();
    if (out.x.size() != n || out.y.size() != n || out.z.size() != n || out.f.size() != n || out.interface.size() != n)
        in.fail("its node arrays differ in length");
    for (const auto* values : {&out.x, &out.y, &out.z, &out.f})
        for (std::size_t v = 0; v < n; ++v)
            if (!std::isfinite((*values)[v]))
                in.fail(std::string(values == &out.f ? "the field value" : "a coordinate") + " of node " +
                        std::to_string(v) + " is not a finite number");
    if (out.tets.size() % 4 != 0) in.fail("its tetrahedra are not four corners each");
    for (const std::int32_t v : out.tets)
        if (v < 0 || static_cast<std::size_t>(v) >= n) in.fail("a tetrahedron refers to node " + std::to_string(v) + " of " + std::to_string(n));
    for (const GlobalId g : out.gid)
        // A solver's ids (a .pvtu's) need not be dense: any that fits an edge key.
        if (g < 0 || g > kMaxGlobalId) in.fail("global id " + std::to_string(g) + " outside [0, 2^32)");
    if (!std::is_sorted(out.shared_edges.begin(), out.shared_edges.end())) in.fail("its shared edges are not sorted");
    return out;
}

} // namespace tetiso
