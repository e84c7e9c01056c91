#include <perideal/io/checkpoint.h>
#include <perideal/io/time_series.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace PeriDEAL
{
  namespace
  {
    /** The header line (without newline). */
    std::string
    join(const std::vector<std::string> &columns)
    {
      std::string line;
      for (std::size_t c = 0; c < columns.size(); ++c)
        line += (c > 0 ? "," : "") + columns[c];
      return line;
    }

    /** One CSV line with 16 significant digits, newline included. */
    std::string
    format_row(const std::vector<double> &row)
    {
      std::string line;
      char        buffer[40];
      for (std::size_t c = 0; c < row.size(); ++c)
        {
          const int n = std::snprintf(buffer, sizeof(buffer), "%.16g", row[c]);
          if (c > 0)
            line += ',';
          line.append(buffer, n);
        }
      return line + '\n';
    }
  } // namespace



  TimeSeries::TimeSeries(const MPI_Comm                  comm,
                         const std::string              &filename,
                         const std::vector<std::string> &columns,
                         const bool                      load_existing_file)
    : mpi_communicator(comm)
    , filename(filename)
    , column_names(columns)
  {
    if (columns.empty())
      throw std::invalid_argument("TimeSeries '" + filename + "': no columns");
    for (const std::string &name : columns)
      if (name.empty() || name.find_first_of(",\"\n\r") != std::string::npos)
        throw std::invalid_argument("TimeSeries '" + filename + "': invalid column name '" +
                                    name +
                                    "' (must be non-empty, without comma, quote or line break)");
    if (load_existing_file)
      load_existing();
  }



  void
  TimeSeries::add_row(const std::vector<double> &values)
  {
    if (values.size() != column_names.size())
      throw std::invalid_argument("TimeSeries '" + filename + "': row of " +
                                  std::to_string(values.size()) + " values for " +
                                  std::to_string(column_names.size()) + " columns");
    data.push_back(values);
    if (rows_on_disk == 0 || rows_on_disk + 1 != data.size())
      {
        write();
        return;
      }
    // Appending one complete line keeps each row O(1): rewriting the file per
    // row would make long runs quadratic. A crash can at most cut the last
    // line, which load_existing() then rejects; truncation and reloading
    // rewrite the file atomically.
    internal::run_on_root(mpi_communicator, [&]() {
      std::ofstream out(filename, std::ios::app | std::ios::binary);
      out << format_row(values);
      out.flush();
      if (!out)
        throw std::runtime_error("Cannot append to time series '" + filename + "'");
    });
    rows_on_disk = data.size();
  }



  void
  TimeSeries::truncate_after(const double time)
  {
    // Rows read back from 16 digits may exceed the exact time slightly.
    const double limit = time + 1e-14 * std::abs(time);
    std::vector<std::vector<double>> kept;
    for (auto &row : data)
      if (!(row[0] > limit))
        kept.push_back(std::move(row));
    data.swap(kept);
    write();
  }



  void
  TimeSeries::write() const
  {
    internal::run_on_root(mpi_communicator, [&]() {
      std::string text = join(column_names) + '\n';
      for (const auto &row : data)
        text += format_row(row);
      write_file_atomically(filename, text);
    });
    rows_on_disk = data.size();
  }



  bool
  TimeSeries::load_existing()
  {
    bool                exists = false;
    std::vector<double> flat;
    internal::run_on_root(mpi_communicator, [&]() {
      exists = std::filesystem::exists(filename);
      if (!exists)
        return;
      std::ifstream in(filename);
      if (!in)
        throw std::runtime_error("Cannot open time series '" + filename + "'");
      std::string line;
      std::getline(in, line);
      if (!line.empty() && line.back() == '\r')
        line.pop_back();
      if (line != join(column_names))
        throw std::runtime_error("Time series '" + filename + "' has the columns '" + line +
                                 "', expected '" + join(column_names) + "'");
      unsigned int line_number = 1;
      while (std::getline(in, line))
        {
          ++line_number;
          if (!line.empty() && line.back() == '\r')
            line.pop_back();
          if (line.empty())
            continue;
          const std::string where =
            "Time series '" + filename + "', line " + std::to_string(line_number);
          std::size_t start = 0;
          for (std::size_t c = 0; c < column_names.size(); ++c)
            {
              const std::size_t end = line.find(',', start);
              if ((c + 1 < column_names.size()) == (end == std::string::npos))
                throw std::runtime_error(where + ": expected " +
                                         std::to_string(column_names.size()) + " values");
              const std::string item = line.substr(start, end - start);
              char             *stop = nullptr;
              const double      x    = std::strtod(item.c_str(), &stop);
              if (item.empty() || stop != item.c_str() + item.size())
                throw std::runtime_error(where + ": cannot parse number '" + item + "'");
              flat.push_back(x);
              start = end + 1;
            }
        }
    });
    if (Utilities::MPI::n_mpi_processes(mpi_communicator) > 1)
      {
        exists = Utilities::MPI::broadcast(mpi_communicator, exists, 0);
        flat   = Utilities::MPI::broadcast(mpi_communicator, flat, 0);
      }

    data.clear();
    for (std::size_t first = 0; first < flat.size(); first += column_names.size())
      data.emplace_back(flat.begin() + first, flat.begin() + first + column_names.size());
    rows_on_disk = exists ? data.size() : 0;
    return exists;
  }
} // namespace PeriDEAL
