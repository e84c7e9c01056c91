#include <deal.II/base/mpi.h>

#include <perideal/io/checkpoint.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numeric>
#include <stdexcept>

#include <unistd.h>

namespace PeriDEAL
{
  namespace internal
  {
    void
    run_on_root(const MPI_Comm comm, const std::function<void()> &f)
    {
      std::string error;
      if (Utilities::MPI::this_mpi_process(comm) == 0)
        {
          try
            {
              f();
            }
          catch (const std::exception &e)
            {
              error = e.what();
              if (error.empty())
                error = "unknown error";
            }
          catch (...)
            {
              error = "unknown error";
            }
        }
      if (Utilities::MPI::n_mpi_processes(comm) > 1)
        error = Utilities::MPI::broadcast(comm, error, 0);
      if (!error.empty())
        throw std::runtime_error(error);
    }
  } // namespace internal

  namespace
  {
    constexpr char          checkpoint_magic[] = "PERIDEAL-CKPT";
    constexpr std::size_t   magic_length       = sizeof(checkpoint_magic) - 1;
    constexpr std::uint32_t byte_order_mark    = 0x01020304u;
    constexpr std::uint32_t format_version     = 1;

    /** Records per block when writing and reading/broadcasting (~8 MB). */
    std::size_t
    block_records(const std::size_t record_bytes)
    {
      return std::max<std::size_t>(1, (std::size_t(8) << 20) / record_bytes);
    }

    /** FNV-1a over 64-bit words: cheap, and catches flipped or lost bytes. */
    struct Checksum
    {
      std::uint64_t value = 14695981039346656037ull;

      void
      add(const char *data, const std::size_t n_bytes)
      {
        // Records are whole words, so n_bytes is a multiple of 8.
        for (std::size_t i = 0; i + 8 <= n_bytes; i += 8)
          {
            std::uint64_t w;
            std::memcpy(&w, data + i, 8);
            value = (value ^ w) * 1099511628211ull;
          }
      }
    };

    /**
     * A file written under a temporary name and renamed to its final name
     * by commit(); if commit() is never reached (exception), the temporary
     * file is removed and an existing file of the final name stays intact.
     */
    class AtomicFile
    {
    public:
      explicit AtomicFile(const std::string &path)
        : path(path)
        , tmp(path + ".tmp")
      {
        file = std::fopen(tmp.c_str(), "wb");
        if (file == nullptr)
          throw std::runtime_error("Cannot open '" + tmp +
                                   "' for writing: " + std::strerror(errno));
      }

      ~AtomicFile()
      {
        if (file != nullptr)
          {
            std::fclose(file);
            std::remove(tmp.c_str());
          }
      }

      AtomicFile(const AtomicFile &) = delete;
      AtomicFile &
      operator=(const AtomicFile &) = delete;

      void
      write(const void *data, const std::size_t n_bytes)
      {
        if (n_bytes > 0 && std::fwrite(data, 1, n_bytes, file) != n_bytes)
          throw std::runtime_error("Cannot write '" + tmp +
                                   "': " + std::strerror(errno));
      }

      void
      write(const std::string &s)
      {
        write(s.data(), s.size());
      }

      template <typename T>
      void
      write_pod(const T &value)
      {
        write(&value, sizeof(T));
      }

      void
      commit()
      {
        // fsync before the rename: otherwise a power loss may leave the new
        // name pointing at an empty file.
        if (std::fflush(file) != 0 || ::fsync(::fileno(file)) != 0)
          throw std::runtime_error("Cannot write '" + tmp +
                                   "': " + std::strerror(errno));
        const int status = std::fclose(file);
        file             = nullptr;
        if (status != 0)
          {
            std::remove(tmp.c_str());
            throw std::runtime_error("Cannot write '" + tmp +
                                     "': " + std::strerror(errno));
          }
        std::error_code ec;
        std::filesystem::rename(tmp, path, ec);
        if (ec)
          {
            std::remove(tmp.c_str());
            throw std::runtime_error("Cannot rename '" + tmp + "' to '" + path +
                                     "': " + ec.message());
          }
      }

    private:
      const std::string path, tmp;
      std::FILE        *file = nullptr;
    };

    /** Throw std::invalid_argument unless @p v has the node layout. */
    template <int dim>
    void
    check_layout(const Vector *v, const Discretization<dim> &disc, const std::string &what)
    {
      if (v == nullptr)
        throw std::invalid_argument(what + ": null vector");
      if (v->locally_owned_size() != disc.n_owned() || v->size() != disc.n_global())
        throw std::invalid_argument(
          what + ": vector of size " + std::to_string(v->size()) + " (" +
          std::to_string(v->locally_owned_size()) +
          " owned) does not have the node layout of the discretization (" +
          std::to_string(disc.n_global()) + " nodes, " + std::to_string(disc.n_owned()) +
          " owned)");
    }

    /** Throw std::invalid_argument for a name that would break a CSV header. */
    void
    check_column_name(const std::string &name, const std::string &what)
    {
      if (name.empty() || name.find_first_of(",\"\n\r") != std::string::npos)
        throw std::invalid_argument(what + ": invalid column name '" + name +
                                    "' (must be non-empty, without comma, quote or "
                                    "line break)");
    }

    /**
     * Gather the ids of all owned nodes and @p n_values numbers per node,
     * filled by @p fill(local index, destination), on rank 0 (unsorted;
     * other ranks get empty vectors).
     */
    template <int dim>
    void
    gather_nodes(const Discretization<dim>                           &disc,
                 const unsigned int                                   n_values,
                 const std::function<void(unsigned int, double *)>   &fill,
                 std::vector<std::uint64_t>                          &ids,
                 std::vector<double>                                 &values)
    {
      const MPI_Comm     comm    = disc.get_mpi_communicator();
      const unsigned int n_owned = disc.n_owned();
      const bool         root    = Utilities::MPI::this_mpi_process(comm) == 0;

      std::vector<std::uint64_t> my_ids(n_owned);
      std::vector<double>        my_values(std::size_t(n_owned) * n_values);
      for (unsigned int i = 0; i < n_owned; ++i)
        {
          my_ids[i] = disc.id[i];
          fill(i, my_values.data() + std::size_t(i) * n_values);
        }

      const std::vector<unsigned int> counts = Utilities::MPI::all_gather(comm, n_owned);
      const std::uint64_t n_total = std::accumulate(counts.begin(), counts.end(), std::uint64_t(0));
      // MPI_Gatherv counts and displacements are int.
      if (n_total * std::max(1u, n_values) > std::uint64_t(INT_MAX))
        throw std::runtime_error("Too many nodes (" + std::to_string(n_total) +
                                 ") to gather on one rank for output");

      std::vector<int> id_counts, id_displs, value_counts, value_displs;
      if (root)
        {
          ids.resize(n_total);
          values.resize(n_total * n_values);
          int offset = 0;
          for (const unsigned int c : counts)
            {
              id_counts.push_back(c);
              id_displs.push_back(offset);
              value_counts.push_back(c * n_values);
              value_displs.push_back(offset * n_values);
              offset += c;
            }
        }
      else
        {
          ids.clear();
          values.clear();
        }

      int ierr = MPI_Gatherv(my_ids.data(), n_owned, MPI_UINT64_T, ids.data(),
                             id_counts.data(), id_displs.data(), MPI_UINT64_T, 0, comm);
      AssertThrowMPI(ierr);
      ierr = MPI_Gatherv(my_values.data(), n_owned * n_values, MPI_DOUBLE, values.data(),
                         value_counts.data(), value_displs.data(), MPI_DOUBLE, 0, comm);
      AssertThrowMPI(ierr);
    }

    /** Sort gathered nodes by id (rank 0); duplicate ids are an error. */
    void
    sort_by_id(std::vector<std::uint64_t> &ids,
               std::vector<double>        &values,
               const unsigned int          n_values)
    {
      std::vector<std::size_t> order(ids.size());
      std::iota(order.begin(), order.end(), std::size_t(0));
      std::sort(order.begin(), order.end(),
                [&](const std::size_t a, const std::size_t b) { return ids[a] < ids[b]; });

      std::vector<std::uint64_t> sorted_ids(ids.size());
      std::vector<double>        sorted_values(values.size());
      for (std::size_t k = 0; k < order.size(); ++k)
        {
          sorted_ids[k] = ids[order[k]];
          std::copy_n(values.begin() + order[k] * n_values, n_values,
                      sorted_values.begin() + k * n_values);
          if (k > 0 && sorted_ids[k] == sorted_ids[k - 1])
            throw std::runtime_error("Node id " + std::to_string(sorted_ids[k]) +
                                     " is owned by two ranks");
        }
      ids.swap(sorted_ids);
      values.swap(sorted_values);
    }

    /** Read a plain value or throw "truncated". */
    template <typename T>
    void
    read_pod(std::istream &in, T &value, const std::string &path)
    {
      in.read(reinterpret_cast<char *>(&value), sizeof(T));
      if (!in)
        throw std::runtime_error("Checkpoint '" + path + "' is truncated (header incomplete)");
    }

    /** Shorten a signature for an error message. */
    std::string
    abbreviate(const std::string &s)
    {
      return s.size() <= 64 ? s : s.substr(0, 61) + "...";
    }

    /** Format a double with 17 significant digits (round trip exact). */
    void
    append_number(std::string &line, const double x)
    {
      char buffer[40];
      const int n = std::snprintf(buffer, sizeof(buffer), "%.17g", x);
      line.append(buffer, n);
    }

    /** Split a CSV line (no quoting: names are validated on writing). */
    std::vector<std::string>
    split_csv(std::string line)
    {
      if (!line.empty() && line.back() == '\r')
        line.pop_back();
      std::vector<std::string> parts;
      std::size_t              start = 0;
      while (true)
        {
          const std::size_t comma = line.find(',', start);
          parts.push_back(line.substr(start, comma - start));
          if (comma == std::string::npos)
            break;
          start = comma + 1;
        }
      return parts;
    }

    /** Parse a whole string as a double or throw. */
    double
    parse_double(const std::string &s, const std::string &where)
    {
      // strtod also reads "nan" and "inf"; range errors of denormals are
      // harmless, so only check that the whole string was consumed.
      char        *end = nullptr;
      const double x   = std::strtod(s.c_str(), &end);
      if (s.empty() || end != s.c_str() + s.size())
        throw std::runtime_error(where + ": cannot parse number '" + s + "'");
      return x;
    }
  } // namespace



  void
  write_file_atomically(const std::string &filename, const std::string &contents)
  {
    AtomicFile file(filename);
    file.write(contents);
    file.commit();
  }



  template <int dim>
  void
  write_checkpoint(const std::string               &path,
                   const Discretization<dim>       &disc,
                   const unsigned int               step,
                   const double                     time,
                   const std::vector<const Vector *> &fields,
                   const std::string               &signature)
  {
    for (unsigned int f = 0; f < fields.size(); ++f)
      check_layout(fields[f], disc, "write_checkpoint: field " + std::to_string(f));

    const unsigned int         n_fields = fields.size();
    std::vector<std::uint64_t> ids;
    std::vector<double>        values;
    gather_nodes<dim>(
      disc, n_fields,
      [&](const unsigned int i, double *out) {
        for (unsigned int f = 0; f < n_fields; ++f)
          out[f] = fields[f]->local_element(i);
      },
      ids, values);

    internal::run_on_root(disc.get_mpi_communicator(), [&]() {
      sort_by_id(ids, values, n_fields);

      AtomicFile file(path);
      file.write(checkpoint_magic, magic_length);
      file.write_pod(byte_order_mark);
      file.write_pod(format_version);
      file.write_pod(std::uint32_t(dim));
      file.write_pod(std::uint64_t(ids.size()));
      file.write_pod(std::uint32_t(n_fields));
      file.write_pod(std::uint64_t(step));
      file.write_pod(time);
      file.write_pod(std::uint64_t(signature.size()));
      file.write(signature);

      // Records id, values... in blocks, so the checksum sees exactly the
      // bytes on disk.
      const std::size_t record_bytes = 8 * (1 + std::size_t(n_fields));
      const std::size_t block        = block_records(record_bytes);
      std::vector<char> buffer;
      Checksum          checksum;
      for (std::size_t first = 0; first < ids.size(); first += block)
        {
          const std::size_t n = std::min(block, ids.size() - first);
          buffer.resize(n * record_bytes);
          for (std::size_t k = 0; k < n; ++k)
            {
              char *record = buffer.data() + k * record_bytes;
              std::memcpy(record, &ids[first + k], 8);
              std::memcpy(record + 8, values.data() + (first + k) * n_fields, 8 * n_fields);
            }
          checksum.add(buffer.data(), buffer.size());
          file.write(buffer.data(), buffer.size());
        }
      file.write_pod(checksum.value);
      file.commit();
    });
  }



  template <int dim>
  bool
  read_checkpoint(const std::string         &path,
                  const Discretization<dim> &disc,
                  unsigned int              &step,
                  double                    &time,
                  const std::vector<Vector *> &fields,
                  const std::string         &signature)
  {
    for (unsigned int f = 0; f < fields.size(); ++f)
      check_layout(fields[f], disc, "read_checkpoint: field " + std::to_string(f));

    const MPI_Comm     comm     = disc.get_mpi_communicator();
    const unsigned int n_fields = fields.size();
    const std::string  where    = "Checkpoint '" + path + "'";

    // Header: rank 0 reads and validates everything that can be checked
    // before a field is touched.
    std::ifstream in;
    bool          exists    = false;
    std::uint64_t file_step = 0;
    double        file_time = 0.;
    internal::run_on_root(comm, [&]() {
      exists = std::filesystem::exists(path);
      if (!exists)
        return;
      in.open(path, std::ios::binary);
      if (!in)
        throw std::runtime_error("Cannot open " + where + " for reading");
      const std::uint64_t file_size = std::filesystem::file_size(path);

      char magic[magic_length];
      in.read(magic, magic_length);
      if (!in || std::memcmp(magic, checkpoint_magic, magic_length) != 0)
        throw std::runtime_error(where + " is not a PeriDEAL checkpoint");
      std::uint32_t bom, version, file_dim, file_n_fields;
      std::uint64_t file_n_nodes, signature_length;
      read_pod(in, bom, path);
      if (bom != byte_order_mark)
        throw std::runtime_error(where + " was written on a machine of another byte order");
      read_pod(in, version, path);
      if (version != format_version)
        throw std::runtime_error(where + " has format version " + std::to_string(version) +
                                 ", this program reads version " +
                                 std::to_string(format_version));
      read_pod(in, file_dim, path);
      read_pod(in, file_n_nodes, path);
      read_pod(in, file_n_fields, path);
      read_pod(in, file_step, path);
      read_pod(in, file_time, path);
      read_pod(in, signature_length, path);

      if (file_dim != dim)
        throw std::runtime_error(where + " was written for dim " + std::to_string(file_dim) +
                                 ", this run has dim " + std::to_string(dim));
      if (file_n_nodes != disc.n_global())
        throw std::runtime_error(where + " has " + std::to_string(file_n_nodes) +
                                 " nodes, the discretization has " +
                                 std::to_string(disc.n_global()));
      if (file_n_fields != n_fields)
        throw std::runtime_error(where + " has " + std::to_string(file_n_fields) +
                                 " fields, " + std::to_string(n_fields) + " were requested");
      if (signature_length > file_size)
        throw std::runtime_error(where + " is malformed (signature length " +
                                 std::to_string(signature_length) + ")");
      std::string file_signature(signature_length, '\0');
      in.read(file_signature.data(), signature_length);
      if (!in)
        throw std::runtime_error(where + " is truncated (header incomplete)");
      if (file_signature != signature)
        throw std::runtime_error(where + " belongs to another setup: its signature '" +
                                 abbreviate(file_signature) + "' differs from '" +
                                 abbreviate(signature) + "'");

      const std::uint64_t expected = std::uint64_t(in.tellg()) +
                                     file_n_nodes * 8 * (1 + std::uint64_t(n_fields)) + 8;
      if (file_size < expected)
        throw std::runtime_error(where + " is truncated (" + std::to_string(file_size) +
                                 " bytes, expected " + std::to_string(expected) + ")");
      if (file_size > expected)
        throw std::runtime_error(where + " is malformed (" + std::to_string(file_size) +
                                 " bytes, expected " + std::to_string(expected) + ")");
    });
    exists = Utilities::MPI::broadcast(comm, exists, 0);
    if (!exists)
      return false;
    file_step = Utilities::MPI::broadcast(comm, file_step, 0);
    file_time = Utilities::MPI::broadcast(comm, file_time, 0);

    // Owned nodes sorted by id, matched against each block by binary search.
    std::vector<std::pair<std::uint64_t, unsigned int>> owned(disc.n_owned());
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      owned[i] = {disc.id[i], i};
    std::sort(owned.begin(), owned.end());

    const std::uint64_t        n_nodes      = disc.n_global();
    const std::size_t          record_bytes = 8 * (1 + std::size_t(n_fields));
    const std::size_t          block        = block_records(record_bytes);
    std::vector<char>          buffer;
    std::vector<std::uint64_t> block_ids;
    std::size_t                next_owned = 0;
    std::uint64_t              n_missing  = 0;
    std::uint64_t              first_missing = std::numeric_limits<std::uint64_t>::max();
    Checksum                   checksum;
    std::uint64_t              last_id = 0;

    const auto note_missing = [&](const std::uint64_t id) {
      ++n_missing;
      first_missing = std::min(first_missing, id);
    };

    for (std::uint64_t first = 0; first < n_nodes; first += block)
      {
        const std::size_t n = std::min<std::uint64_t>(block, n_nodes - first);
        buffer.resize(n * record_bytes);
        internal::run_on_root(comm, [&]() {
          in.read(buffer.data(), buffer.size());
          if (!in)
            throw std::runtime_error(where + " could not be read (truncated?)");
          checksum.add(buffer.data(), buffer.size());
          // Strictly increasing ids: required by the binary search below.
          for (std::size_t k = 0; k < n; ++k)
            {
              std::uint64_t id;
              std::memcpy(&id, buffer.data() + k * record_bytes, 8);
              if ((first + k > 0) && id <= last_id)
                throw std::runtime_error(where + " is malformed (node ids not sorted)");
              last_id = id;
            }
        });
        Utilities::MPI::broadcast(buffer.data(), buffer.size(), 0, comm);

        block_ids.resize(n);
        for (std::size_t k = 0; k < n; ++k)
          std::memcpy(&block_ids[k], buffer.data() + k * record_bytes, 8);

        for (; next_owned < owned.size() && owned[next_owned].first <= block_ids.back();
             ++next_owned)
          {
            const std::uint64_t id = owned[next_owned].first;
            const auto          p  = std::lower_bound(block_ids.begin(), block_ids.end(), id);
            if (p == block_ids.end() || *p != id)
              {
                note_missing(id);
                continue;
              }
            const char *record = buffer.data() + (p - block_ids.begin()) * record_bytes;
            for (unsigned int f = 0; f < n_fields; ++f)
              {
                double value;
                std::memcpy(&value, record + 8 * (1 + f), 8);
                fields[f]->local_element(owned[next_owned].second) = value;
              }
          }
      }
    for (; next_owned < owned.size(); ++next_owned)
      note_missing(owned[next_owned].first);

    internal::run_on_root(comm, [&]() {
      std::uint64_t stored;
      in.read(reinterpret_cast<char *>(&stored), 8);
      if (!in)
        throw std::runtime_error(where + " is truncated (checksum missing)");
      if (stored != checksum.value)
        throw std::runtime_error(where + " is corrupted (checksum mismatch)");
    });

    // Plain MPI: deal.II 9.4.1's Utilities::MPI::min<unsigned long> gets
    // values >= 2^63 (our "none" marker) wrong.
    int ierr = MPI_Allreduce(MPI_IN_PLACE, &n_missing, 1, MPI_UINT64_T, MPI_SUM, comm);
    AssertThrowMPI(ierr);
    ierr = MPI_Allreduce(MPI_IN_PLACE, &first_missing, 1, MPI_UINT64_T, MPI_MIN, comm);
    AssertThrowMPI(ierr);
    if (n_missing > 0)
      throw std::runtime_error(where + " does not contain " + std::to_string(n_missing) +
                               " node(s) of the discretization, e.g. id " +
                               std::to_string(first_missing));

    step = file_step;
    time = file_time;
    return true;
  }



  template <int dim>
  void
  write_node_table(const std::string &path,
                   const Discretization<dim> &disc,
                   const std::vector<std::pair<std::string, const Vector *>> &fields)
  {
    for (const auto &field : fields)
      {
        check_column_name(field.first, "write_node_table");
        check_layout(field.second, disc, "write_node_table: field '" + field.first + "'");
      }

    const unsigned int         n_values = dim + fields.size();
    std::vector<std::uint64_t> ids;
    std::vector<double>        values;
    gather_nodes<dim>(
      disc, n_values,
      [&](const unsigned int i, double *out) {
        for (unsigned int d = 0; d < dim; ++d)
          out[d] = disc.position[i][d];
        for (unsigned int f = 0; f < fields.size(); ++f)
          out[dim + f] = fields[f].second->local_element(i);
      },
      ids, values);

    internal::run_on_root(disc.get_mpi_communicator(), [&]() {
      sort_by_id(ids, values, n_values);

      AtomicFile  file(path);
      std::string text = "id";
      const char *coordinate_names[] = {"x", "y", "z"};
      for (unsigned int d = 0; d < dim; ++d)
        text += std::string(",") + coordinate_names[d];
      for (const auto &field : fields)
        text += "," + field.first;
      text += '\n';

      for (std::size_t k = 0; k < ids.size(); ++k)
        {
          text += std::to_string(ids[k]);
          for (unsigned int c = 0; c < n_values; ++c)
            {
              text += ',';
              append_number(text, values[k * n_values + c]);
            }
          text += '\n';
          if (text.size() > (1u << 20))
            {
              file.write(text);
              text.clear();
            }
        }
      file.write(text);
      file.commit();
    });
  }



  double
  compare_node_tables(const std::string &a, const std::string &b)
  {
    std::ifstream in_a(a), in_b(b);
    if (!in_a)
      throw std::runtime_error("Cannot open node table '" + a + "'");
    if (!in_b)
      throw std::runtime_error("Cannot open node table '" + b + "'");

    std::string line_a, line_b;
    if (!std::getline(in_a, line_a) || !std::getline(in_b, line_b))
      throw std::runtime_error("Node table '" + a + "' or '" + b + "' is empty");
    const std::vector<std::string> header = split_csv(line_a);
    if (header != split_csv(line_b))
      throw std::runtime_error("Node tables '" + a + "' and '" + b +
                               "' have different columns");
    if (header.empty() || header[0] != "id")
      throw std::runtime_error("Node table '" + a + "' does not start with the column 'id'");
    std::size_t first_field = 1;
    while (first_field < header.size() && first_field <= 3 &&
           header[first_field] == std::string(1, "xyz"[first_field - 1]))
      ++first_field;

    double      max_difference = 0.;
    std::size_t row            = 0;
    while (true)
      {
        // Skip empty lines (a trailing newline, say).
        bool got_a, got_b;
        while ((got_a = static_cast<bool>(std::getline(in_a, line_a))) &&
               (line_a.empty() || line_a == "\r"))
          ;
        while ((got_b = static_cast<bool>(std::getline(in_b, line_b))) &&
               (line_b.empty() || line_b == "\r"))
          ;
        if (!got_a && !got_b)
          break;
        ++row;
        if (got_a != got_b)
          throw std::runtime_error("Node tables '" + a + "' and '" + b +
                                   "' have different numbers of rows");
        const std::vector<std::string> row_a = split_csv(line_a), row_b = split_csv(line_b);
        const std::string where = "Node table row " + std::to_string(row);
        if (row_a.size() != header.size() || row_b.size() != header.size())
          throw std::runtime_error(where + ": wrong number of columns");
        if (row_a[0] != row_b[0])
          throw std::runtime_error(where + ": ids differ ('" + row_a[0] + "' in '" + a +
                                   "', '" + row_b[0] + "' in '" + b + "')");
        for (std::size_t c = first_field; c < header.size(); ++c)
          {
            const double x = parse_double(row_a[c], where + " of '" + a + "'");
            const double y = parse_double(row_b[c], where + " of '" + b + "'");
            if (std::isnan(x) || std::isnan(y))
              {
                if (std::isnan(x) != std::isnan(y))
                  max_difference = std::numeric_limits<double>::infinity();
              }
            else if (x != y) // also equal infinities
              max_difference = std::max(max_difference, std::abs(x - y));
          }
      }
    return max_difference;
  }



#define PERIDEAL_INSTANTIATE(dim)                                                        \
  template void write_checkpoint<dim>(const std::string &,                              \
                                      const Discretization<dim> &,                      \
                                      const unsigned int,                               \
                                      const double,                                     \
                                      const std::vector<const Vector *> &,              \
                                      const std::string &);                             \
  template bool read_checkpoint<dim>(const std::string &,                               \
                                     const Discretization<dim> &,                       \
                                     unsigned int &,                                    \
                                     double &,                                          \
                                     const std::vector<Vector *> &,                     \
                                     const std::string &);                              \
  template void write_node_table<dim>(                                                  \
    const std::string &,                                                                \
    const Discretization<dim> &,                                                        \
    const std::vector<std::pair<std::string, const Vector *>> &);
  PERIDEAL_INSTANTIATE(1)
  PERIDEAL_INSTANTIATE(2)
  PERIDEAL_INSTANTIATE(3)
#undef PERIDEAL_INSTANTIATE
} // namespace PeriDEAL
