// Tests of the I/O module: checkpoints (round trip, rank independence,
// error handling), node tables, CSV time series and ParaView node output.
// Every sub-test works on any number of ranks.

#include <perideal/discretization/discretization.h>
#include <perideal/discretization/domain.h>
#include <perideal/io/checkpoint.h>
#include <perideal/io/node_output.h>
#include <perideal/io/time_series.h>

#include "check.h"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

using namespace PeriDEAL;
using namespace PeriDEALTests;

namespace
{
  // Not dealii::Vector, which the using-directives also bring in.
  using Vector = PeriDEAL::Vector;

  /** The 11 x 11 lattice on the unit square, on @p comm. */
  std::unique_ptr<Discretization<2>>
  make_discretization(const MPI_Comm comm)
  {
    auto              disc = std::make_unique<Discretization<2>>(comm);
    BoxDomain<2>      box(Point<2>(0., 0.), Point<2>(1., 1.));
    LatticeParameters parameters;
    parameters.dx    = 0.1;
    parameters.delta = 0.3;
    disc->setup(box, parameters);
    return disc;
  }

  /** Two fields that depend only on the node (not on the partition). */
  void
  fill_fields(const Discretization<2> &disc, Vector &u, Vector &v)
  {
    disc.initialize_vector(u);
    disc.initialize_vector(v);
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        const Point<2> &x  = disc.position[i];
        u.local_element(i) = std::sin(3. * x[0]) + x[1] / 3.;
        v.local_element(i) = 1e-3 * disc.id[i] + 0.5;
      }
  }

  /** Max |a - b| over all nodes. */
  double
  max_difference(const Vector &a, const Vector &b)
  {
    double d = 0.;
    for (unsigned int i = 0; i < a.locally_owned_size(); ++i)
      d = std::max(d, std::abs(a.local_element(i) - b.local_element(i)));
    return Utilities::MPI::max(d, MPI_COMM_WORLD);
  }

  /** Rank 0's value of @p b, on all ranks, so all ranks check the same. */
  bool
  on_root(const std::function<bool()> &f)
  {
    bool ok = root() ? f() : false;
    return Utilities::MPI::broadcast(MPI_COMM_WORLD, ok, 0);
  }

  std::string
  read_file(const std::string &name)
  {
    std::ifstream      in(name, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
  }

  std::vector<std::string>
  read_lines(const std::string &name)
  {
    std::ifstream            in(name);
    std::vector<std::string> lines;
    for (std::string line; std::getline(in, line);)
      lines.push_back(line);
    return lines;
  }

  unsigned int
  count(const std::string &text, const std::string &what)
  {
    unsigned int n = 0;
    for (std::size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + 1))
      ++n;
    return n;
  }

  /** True if @p f throws an exception of type E on this rank. */
  template <typename E, typename F>
  bool
  throws(F &&f)
  {
    try
      {
        f();
      }
    catch (const E &e)
      {
        if (root())
          std::cout << "        (" << e.what() << ")" << std::endl;
        return true;
      }
    return false;
  }

  void
  test_checkpoint()
  {
    const MPI_Comm comm = MPI_COMM_WORLD;
    auto           disc = make_discretization(comm);
    Vector         u, v;
    fill_fields(*disc, u, v);
    const Vector u0 = u, v0 = v;

    write_checkpoint("checkpoint.bin", *disc, 7, 0.125, {&u, &v}, "signature A");
    check(on_root([] { return !std::filesystem::exists("checkpoint.bin.tmp"); }),
          "no temporary file left");

    u = 0.;
    v = 0.;
    unsigned int step = 0;
    double       time = 0.;
    check(read_checkpoint("checkpoint.bin", *disc, step, time, {&u, &v}, "signature A"),
          "checkpoint found");
    check(step == 7 && time == 0.125, "step and time restored");
    check(max_difference(u, u0) == 0. && max_difference(v, v0) == 0.,
          "fields restored exactly");

    // The same data written on one rank must give the same bytes, and that
    // file must be readable on the current ranks.
    if (root())
      {
        auto   serial = make_discretization(MPI_COMM_SELF);
        Vector su, sv;
        fill_fields(*serial, su, sv);
        write_checkpoint("checkpoint_serial.bin", *serial, 7, 0.125, {&su, &sv},
                         "signature A");
      }
    check(on_root([] {
            return read_file("checkpoint.bin") == read_file("checkpoint_serial.bin");
          }),
          "checkpoint independent of the number of ranks (" +
            std::to_string(Utilities::MPI::n_mpi_processes(comm)) + " vs 1)");
    u = 0.;
    v = 0.;
    check(read_checkpoint("checkpoint_serial.bin", *disc, step, time, {&u, &v}, "signature A"),
          "serial checkpoint found");
    check(max_difference(u, u0) == 0. && max_difference(v, v0) == 0.,
          "serial checkpoint restored exactly");

    check(!read_checkpoint("missing.bin", *disc, step, time, {&u, &v}, "signature A"),
          "missing file returns false");
    check(throws<std::runtime_error>([&] {
            read_checkpoint("checkpoint.bin", *disc, step, time, {&u, &v}, "signature B");
          }),
          "signature mismatch throws");
    check(throws<std::runtime_error>([&] {
            read_checkpoint("checkpoint.bin", *disc, step, time, {&u}, "signature A");
          }),
          "field count mismatch throws");

    // Damaged copies: cut off, one flipped bit in the data, not a checkpoint.
    const std::uintmax_t size = std::filesystem::file_size("checkpoint.bin");
    if (root())
      {
        for (const char *name : {"truncated.bin", "corrupted.bin"})
          std::filesystem::copy_file("checkpoint.bin", name,
                                     std::filesystem::copy_options::overwrite_existing);
        std::filesystem::resize_file("truncated.bin", size - 20);
        std::fstream f("corrupted.bin", std::ios::in | std::ios::out | std::ios::binary);
        f.seekp(size - 12);
        f.put(0x55);
        std::ofstream("garbage.bin") << "not a checkpoint at all\n";

        // A valid file with another id in the last record (checksum redone
        // as documented: FNV-1a over the 64-bit words of the records).
        std::string       bytes         = read_file("checkpoint.bin");
        const std::size_t records_bytes = disc->n_global() * 8 * 3;
        const std::size_t records_start = bytes.size() - 8 - records_bytes;
        const std::uint64_t foreign_id  = 1000000;
        std::memcpy(&bytes[bytes.size() - 8 - 24], &foreign_id, 8);
        std::uint64_t checksum = 14695981039346656037ull;
        for (std::size_t i = records_start; i < bytes.size() - 8; i += 8)
          {
            std::uint64_t w;
            std::memcpy(&w, &bytes[i], 8);
            checksum = (checksum ^ w) * 1099511628211ull;
          }
        std::memcpy(&bytes[bytes.size() - 8], &checksum, 8);
        std::ofstream("foreign_id.bin", std::ios::binary) << bytes;
      }
    MPI_Barrier(comm);
    check(throws<std::runtime_error>([&] {
            read_checkpoint("truncated.bin", *disc, step, time, {&u, &v}, "signature A");
          }),
          "truncated file throws");
    check(throws<std::runtime_error>([&] {
            read_checkpoint("corrupted.bin", *disc, step, time, {&u, &v}, "signature A");
          }),
          "corrupted file throws");
    check(throws<std::runtime_error>([&] {
            read_checkpoint("garbage.bin", *disc, step, time, {&u, &v}, "signature A");
          }),
          "foreign file throws");
    check(throws<std::runtime_error>([&] {
            read_checkpoint("foreign_id.bin", *disc, step, time, {&u, &v}, "signature A");
          }),
          "file without an owned node id throws");
  }

  void
  test_node_table()
  {
    const MPI_Comm comm = MPI_COMM_WORLD;
    auto           disc = make_discretization(comm);
    Vector         u, v;
    fill_fields(*disc, u, v);

    write_node_table("table_a.csv", *disc, {{"u", &u}, {"v", &v}});
    check(on_root([&] {
            const auto lines = read_lines("table_a.csv");
            return lines.size() == disc->n_global() + 1 && lines[0] == "id,x,y,u,v";
          }),
          "table has header and one row per node");
    check(compare_node_tables("table_a.csv", "table_a.csv") == 0., "same table: difference 0");

    // Change u at the node of smallest id, wherever it lives.
    std::uint64_t min_id = std::numeric_limits<std::uint64_t>::max();
    for (unsigned int i = 0; i < disc->n_owned(); ++i)
      min_id = std::min<std::uint64_t>(min_id, disc->id[i]);
    // Not Utilities::MPI::min: wrong for unsigned long >= 2^63 in deal.II 9.4.1.
    MPI_Allreduce(MPI_IN_PLACE, &min_id, 1, MPI_UINT64_T, MPI_MIN, comm);
    for (unsigned int i = 0; i < disc->n_owned(); ++i)
      if (disc->id[i] == min_id)
        u.local_element(i) += 0.25;
    write_node_table("table_b.csv", *disc, {{"u", &u}, {"v", &v}});
    check_close(compare_node_tables("table_a.csv", "table_b.csv"), 0.25, 1e-12,
                "one value changed by 0.25");

    write_node_table("table_c.csv", *disc, {{"u", &u}});
    check(throws<std::runtime_error>([] { compare_node_tables("table_a.csv", "table_c.csv"); }),
          "different columns throw");

    // Rank independence of the table.
    if (root())
      {
        auto   serial = make_discretization(MPI_COMM_SELF);
        Vector su, sv;
        fill_fields(*serial, su, sv);
        write_node_table("table_serial.csv", *serial, {{"u", &su}, {"v", &sv}});
      }
    check(on_root([] { return read_file("table_a.csv") == read_file("table_serial.csv"); }),
          "table independent of the number of ranks");
  }

  void
  test_time_series()
  {
    const MPI_Comm comm = MPI_COMM_WORLD;
    if (root())
      std::filesystem::remove("series.csv");
    MPI_Barrier(comm);

    TimeSeries series(comm, "series.csv", {"time", "energy"});
    check(on_root([] { return !std::filesystem::exists("series.csv"); }),
          "constructor does not touch the file");
    series.add_row({0., 1.});
    series.add_row({0.1, 2.});
    series.add_row({0.2, 1. / 3.});
    check(on_root([] {
            return read_lines("series.csv") ==
                   std::vector<std::string>{"time,energy", "0,1", "0.1,2",
                                            "0.2,0.3333333333333333"};
          }),
          "file has header and rows with 16 digits");
    check(on_root([] { return !std::filesystem::exists("series.csv.tmp"); }),
          "no temporary file left");
    check(throws<std::invalid_argument>([&] { series.add_row({1.}); }),
          "wrong row size throws");

    series.truncate_after(0.1);
    check(series.rows().size() == 2 &&
            on_root([] { return read_lines("series.csv").size() == 3; }),
          "truncate_after(0.1) keeps two rows");

    TimeSeries restarted(comm, "series.csv", {"time", "energy"}, true);
    check(restarted.rows().size() == 2 && restarted.rows()[1][0] == 0.1 &&
            restarted.rows()[1][1] == 2.,
          "load_existing reads the rows back");
    restarted.add_row({0.3, 4.});
    check(on_root([] { return read_lines("series.csv").back() == "0.3,4"; }),
          "restarted series continues the file");

    TimeSeries other(comm, "series.csv", {"time", "other"});
    check(throws<std::runtime_error>([&] { other.load_existing(); }),
          "load_existing with other columns throws");
    TimeSeries fresh(comm, "missing.csv", {"time"});
    check(!fresh.load_existing() && fresh.rows().empty(), "load_existing of missing file");
  }

  void
  test_node_output()
  {
    const MPI_Comm     comm    = MPI_COMM_WORLD;
    const unsigned int n_ranks = Utilities::MPI::n_mpi_processes(comm);
    if (root())
      std::filesystem::remove_all("vis");
    MPI_Barrier(comm);

    auto   disc = make_discretization(comm);
    Vector u, v;
    fill_fields(*disc, u, v);

    NodeOutput<2>     output(*disc, "vis");
    const std::string first  = output.write(0., 0, {{"u", &u}, {"v", &v}});
    const std::string second = output.write(0.5, 10, {{"u", &u}, {"v", &v}});
    check(first == "solution_00000.pvtu" && second == "solution_00001.pvtu",
          "pvtu names " + first + ", " + second);
    check(on_root([&] {
            return std::filesystem::exists("vis/" + first) &&
                   std::filesystem::exists("vis/" + second) &&
                   std::filesystem::exists("vis/solution.pvd");
          }),
          "pvtu and pvd files exist");
    check(on_root([&] {
            const std::string pvd = read_file("vis/solution.pvd");
            return count(pvd, "<DataSet") == 2 && count(pvd, first) == 1 &&
                   count(pvd, second) == 1 && count(pvd, "timestep=\"0.5\"") == 1;
          }),
          "pvd lists both snapshots");

    // One piece per rank, together holding every node once with all fields.
    check(on_root([&] {
            unsigned int n_pieces = 0, n_points = 0;
            bool         names    = true;
            for (const auto &entry : std::filesystem::directory_iterator("vis"))
              {
                const std::string name = entry.path().filename().string();
                if (name.rfind("solution_00000.", 0) != 0 || entry.path().extension() != ".vtu")
                  continue;
                ++n_pieces;
                const std::string vtu = read_file(entry.path().string());
                const std::size_t p   = vtu.find("NumberOfPoints=\"");
                if (p != std::string::npos)
                  n_points += std::stoul(vtu.substr(p + 16));
                for (const char *field : {"\"u\"", "\"v\"", "\"rank\"", "\"region\"", "\"node_id\""})
                  names = names && vtu.find(field) != std::string::npos;
              }
            std::cout << "        " << n_pieces << " pieces, " << n_points << " points"
                      << std::endl;
            return n_pieces == n_ranks && n_points == disc->n_global() && names;
          }),
          "one vtu per rank with all nodes and fields");

    check(throws<std::invalid_argument>([&] { output.write(1., 20, {{"rank", &u}}); }),
          "reserved field name throws");

    // A run restarted at t = 0 continues with snapshot 1.
    NodeOutput<2> restarted(*disc, "vis");
    restarted.restart(0.);
    check(restarted.get_counter() == 1 && restarted.get_records().size() == 1,
          "restart keeps the snapshots up to the restart time");
    const std::string next = restarted.write(1. / 3., 5, {{"u", &u}, {"v", &v}});
    check(next == "solution_00001.pvtu" && on_root([&] {
            const std::string pvd = read_file("vis/solution.pvd");
            return count(pvd, "<DataSet") == 2 &&
                   count(pvd, "timestep=\"0.333333333333\"") == 1 &&
                   count(pvd, "timestep=\"0.5\"") == 0;
          }),
          "restarted series overwrites the later snapshots");

    // Times in the pvd file are rounded (2/3 to 0.666666666667 > 2/3); a
    // restart at the time of the last snapshot must still keep it.
    restarted.write(2. / 3., 6, {{"u", &u}, {"v", &v}});
    NodeOutput<2> again(*disc, "vis");
    again.restart(2. / 3.);
    check(again.get_counter() == 3 && again.get_records().size() == 3,
          "restart at the rounded time of the last snapshot keeps it");
  }
} // namespace

int
main(int argc, char **argv)
{
  return run(argc, argv,
             {{"checkpoint", test_checkpoint},
              {"node_table", test_node_table},
              {"time_series", test_time_series},
              {"node_output", test_node_output}});
}
