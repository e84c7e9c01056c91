#include <deal.II/base/data_out_base.h>
#include <deal.II/base/mpi.h>

#include <perideal/io/checkpoint.h>
#include <perideal/io/node_output.h>

// Serialization of the vectors broadcast by restart().
#include <boost/serialization/string.hpp>
#include <boost/serialization/vector.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace PeriDEAL
{
  namespace
  {
    /**
     * The nodes as deal.II patches: one dim = 0 patch (a vertex) per owned
     * node, as Particles::DataOut does for particles, so the VTU/PVTU
     * writers of DataOutInterface can be used unchanged.
     */
    template <int dim>
    class NodePatches : public DataOutInterface<0, dim>
    {
    public:
      std::vector<DataOutBase::Patch<0, dim>> patches;
      std::vector<std::string>                names;

    private:
      const std::vector<DataOutBase::Patch<0, dim>> &
      get_patches() const override
      {
        return patches;
      }

      std::vector<std::string>
      get_dataset_names() const override
      {
        return names;
      }
    };

    /** The value of attribute @p key="..." in @p line, or false. */
    bool
    xml_attribute(const std::string &line, const std::string &key, std::string &value)
    {
      const std::string pattern = key + "=\"";
      const std::size_t start   = line.find(pattern);
      if (start == std::string::npos)
        return false;
      const std::size_t end = line.find('"', start + pattern.size());
      if (end == std::string::npos)
        return false;
      value = line.substr(start + pattern.size(), end - start - pattern.size());
      return true;
    }
  } // namespace



  template <int dim>
  NodeOutput<dim>::NodeOutput(const Discretization<dim> &discretization,
                              const std::string         &directory,
                              const std::string         &basename)
    : discretization(discretization)
    , directory(directory)
    , basename(basename)
  {
    if (basename.empty() || basename.find('/') != std::string::npos)
      throw std::invalid_argument("NodeOutput: invalid base name '" + basename + "'");
    internal::run_on_root(discretization.get_mpi_communicator(), [&]() {
      if (!directory.empty())
        std::filesystem::create_directories(directory);
    });
  }



  template <int dim>
  std::string
  NodeOutput<dim>::pvd_filename() const
  {
    return (directory.empty() ? "" : directory + "/") + basename + ".pvd";
  }



  template <int dim>
  std::string
  NodeOutput<dim>::write(const double                                                  time,
                         const unsigned int                                            step,
                         const std::vector<std::pair<std::string, const Vector *>> &fields)
  {
    const Discretization<dim> &disc    = discretization;
    const MPI_Comm             comm    = disc.get_mpi_communicator();
    const unsigned int         n_owned = disc.n_owned();

    NodePatches<dim> out;
    for (const auto &field : fields)
      {
        const std::string &name = field.first;
        if (name.empty() || name == "rank" || name == "region" || name == "node_id")
          throw std::invalid_argument("NodeOutput: field name '" + name +
                                      "' is empty or reserved");
        if (field.second == nullptr || field.second->locally_owned_size() != n_owned ||
            field.second->size() != disc.n_global())
          throw std::invalid_argument("NodeOutput: field '" + name +
                                      "' does not have the node layout of the discretization");
        out.names.push_back(name);
      }
    out.names.insert(out.names.end(), {"rank", "region", "node_id"});

    const unsigned int n_fields = fields.size();
    const float        rank     = Utilities::MPI::this_mpi_process(comm);
    out.patches.resize(n_owned);
    for (unsigned int i = 0; i < n_owned; ++i)
      {
        DataOutBase::Patch<0, dim> &patch = out.patches[i];
        patch.vertices[0]                 = disc.position[i];
        patch.patch_index                 = i;
        patch.data.reinit(n_fields + 3, 1);
        for (unsigned int f = 0; f < n_fields; ++f)
          patch.data(f, 0) = fields[f].second->local_element(i);
        patch.data(n_fields, 0)     = rank;
        patch.data(n_fields + 1, 0) = disc.region[i];
        patch.data(n_fields + 2, 0) = disc.id[i];
      }

    DataOutBase::VtkFlags flags;
    flags.time  = time;
    flags.cycle = step;
    // Snapshots are frequent and point data compress poorly: favour speed.
    flags.compression_level = DataOutBase::VtkFlags::best_speed;
    out.set_flags(flags);

    // The writer throws on the rank whose file failed only; turn that into an
    // exception on all ranks instead of a hang in the next collective call.
    std::string pvtu_name, error;
    try
      {
        pvtu_name = out.write_vtu_with_pvtu_record(directory.empty() ? "" : directory + "/",
                                                   basename, counter, comm, 5, 0);
      }
    catch (const std::exception &e)
      {
        error = std::string("NodeOutput: writing snapshot ") + std::to_string(counter) +
                " failed: " + e.what();
      }
    if (Utilities::MPI::max(error.empty() ? 0 : 1, comm) != 0)
      throw std::runtime_error(error.empty() ?
                                 "NodeOutput: writing snapshot " + std::to_string(counter) +
                                   " failed on another rank" :
                                 error);

    records.emplace_back(time, pvtu_name);
    ++counter;
    write_pvd();
    return pvtu_name;
  }



  template <int dim>
  void
  NodeOutput<dim>::restart(const double time)
  {
    const MPI_Comm           comm = discretization.get_mpi_communicator();
    std::vector<double>      times;
    std::vector<std::string> names;
    unsigned int             next = 0;
    internal::run_on_root(comm, [&]() {
      std::ifstream in(pvd_filename());
      if (!in)
        return; // no earlier series: start afresh
      // write_pvd_record() prints times with 12 digits.
      const double limit  = time + 1e-10 * std::abs(time);
      const std::string prefix = basename + "_";
      std::string  line, t, file;
      while (std::getline(in, line))
        if (xml_attribute(line, "timestep", t) && xml_attribute(line, "file", file))
          {
            const double snapshot_time = std::strtod(t.c_str(), nullptr);
            if (snapshot_time > limit)
              continue;
            times.push_back(snapshot_time);
            names.push_back(file);
            // Continue after the number in basename_NNNNN.pvtu.
            unsigned int number = names.size() - 1;
            if (file.compare(0, prefix.size(), prefix) == 0)
              number = std::strtoul(file.c_str() + prefix.size(), nullptr, 10);
            next = std::max(next, number + 1);
          }
    });
    if (Utilities::MPI::n_mpi_processes(comm) > 1)
      {
        times = Utilities::MPI::broadcast(comm, times, 0);
        names = Utilities::MPI::broadcast(comm, names, 0);
        next  = Utilities::MPI::broadcast(comm, next, 0);
      }

    std::vector<std::pair<double, std::string>> kept;
    for (unsigned int k = 0; k < times.size(); ++k)
      kept.emplace_back(times[k], names[k]);
    set_records(next, kept);
  }



  template <int dim>
  void
  NodeOutput<dim>::set_records(const unsigned int                                 next_counter,
                               const std::vector<std::pair<double, std::string>> &new_records)
  {
    counter = next_counter;
    records = new_records;
    write_pvd();
  }



  template <int dim>
  void
  NodeOutput<dim>::write_pvd() const
  {
    internal::run_on_root(discretization.get_mpi_communicator(), [&]() {
      std::ostringstream s;
      DataOutBase::write_pvd_record(s, records);
      write_file_atomically(pvd_filename(), s.str());
    });
  }



  template class NodeOutput<1>;
  template class NodeOutput<2>;
  template class NodeOutput<3>;
} // namespace PeriDEAL
