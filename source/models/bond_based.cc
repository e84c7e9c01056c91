#include <deal.II/base/mpi.h>

#include <perideal/models/bond_damage.h>
#include <perideal/base/exceptions.h>
#include <perideal/models/bond_based.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

#include <perideal/models/lattice_sweep_kernel.h>

// The list loops also need AVX512BW (byte masks of the broken flags).
#if defined(PERIDEAL_LATTICE_SWEEP_AVX512) && defined(__AVX512BW__)
#  define PERIDEAL_PMB_AVX512 1
#endif

namespace PeriDEAL
{
  void
  BondBasedModelParameters::declare_parameters(ParameterHandler &prm)
  {
    prm.declare_entry("Influence function", "constant", Patterns::Selection("constant|linear"),
                      "omega_0 = 1 (2.12) or omega_1 = 1 - r/delta (2.13).");
    prm.declare_entry("Young's modulus", "1", Patterns::Double(),
                      "E (> 0); the micromodulus c is computed from it by matching the "
                      "energy of an isotropic expansion (2.31) unless 'Micromodulus' > 0.");
    prm.declare_entry("Micromodulus", "0", Patterns::Double(), "c, used as given if > 0.");
    prm.declare_entry("Plane", "stress", Patterns::Selection("stress|strain"),
                      "2D only: plane stress (nu = 1/3) or plane strain (nu = 1/4).");
    prm.declare_entry("Linearized", "false", Patterns::Bool(),
                      "Use the linearized bond force (2.32) instead of (2.29)-(2.30).");
    prm.declare_entry("Fracture energy", "0", Patterns::Double(),
                      "G0 (>= 0); the critical stretch is computed from it (2.35) unless "
                      "'Critical stretch' > 0. Both 0: no bond breaking.");
    prm.declare_entry("Critical stretch", "0", Patterns::Double(), "s0, used as given if > 0.");
  }

  void
  BondBasedModelParameters::parse_parameters(ParameterHandler &prm)
  {
    omega = parse_influence_function(prm.get("Influence function"), "Model/Influence function");
    youngs_modulus   = prm.get_double("Young's modulus");
    micromodulus     = prm.get_double("Micromodulus");
    plane_stress     = prm.get("Plane") == "stress";
    linearized       = prm.get_bool("Linearized");
    fracture_energy  = prm.get_double("Fracture energy");
    critical_stretch = prm.get_double("Critical stretch");
    check_parameter(micromodulus >= 0., "Model/Micromodulus", micromodulus,
                    "a non-negative number (0: compute from Young's modulus)");
    if (micromodulus == 0.)
      check_parameter(youngs_modulus > 0., "Model/Young's modulus", youngs_modulus,
                      "a positive number");
    check_parameter(fracture_energy >= 0., "Model/Fracture energy", fracture_energy,
                    "a non-negative number (0: no breaking unless 'Critical stretch' > 0)");
    check_parameter(critical_stretch >= 0., "Model/Critical stretch", critical_stretch,
                    "a non-negative number (0: compute from 'Fracture energy')");
  }

  double
  isotropic_expansion_energy(const unsigned int dim, const double E, const bool plane_stress)
  {
    switch (dim)
      {
        case 1:
          return 0.5 * E;
        case 2:
          {
            // W = mu eps:eps + lambda/2 tr(eps)^2 = 2 (lambda + mu) eps^2 for
            // plane strain; plane stress has the 2D bulk modulus E/(2(1-nu)).
            const double nu = plane_stress ? 1. / 3. : 0.25;
            return plane_stress ? 2. * E / (2. * (1. - nu)) :
                                  2. * E / (2. * (1. + nu) * (1. - 2. * nu));
          }
        case 3:
          return 4.5 * E / (3. * (1. - 2. * 0.25));
        default:
          throw ParameterError("dimension", std::to_string(dim), "1, 2 or 3");
      }
  }

  namespace
  {
    double
    unit_sphere_area(const unsigned int dim)
    {
      return dim == 1 ? 2. : dim == 2 ? 2. * M_PI : 4. * M_PI;
    }
  } // namespace

  double
  bond_based_micromodulus(const unsigned int      dim,
                          const InfluenceFunction omega,
                          const double            delta,
                          const double            E,
                          const bool              plane_stress)
  {
    const double integral = unit_sphere_area(dim) * radial_moment(omega, delta, dim);
    return 4. * isotropic_expansion_energy(dim, E, plane_stress) / integral;
  }

  double
  bond_based_critical_stretch(const unsigned int      dim,
                              const InfluenceFunction omega,
                              const double            delta,
                              const double            c,
                              const double            G0)
  {
    // G0 = sum of the energies c omega s0^2 r / 2 of all bonds crossing a unit
    // crack area. Integrating first over the normal distance z < r of the
    // lower end point leaves, per bond length r, the factor r (1D: one
    // direction), 2 r^2 int_0^1 acos(t) dt = 2 r^2 (2D) and
    // 2 pi r^2 * r/2 (3D, the spherical cap), giving the prefactors below
    // times int_0^delta omega r^{d+1} dr.
    const double prefactor = dim == 1 ? 0.5 : dim == 2 ? 1. : 0.5 * M_PI;
    const double energy_per_s2 = prefactor * c * radial_moment(omega, delta, dim + 1.);
    return std::sqrt(G0 / energy_per_s2);
  }

  template <int dim>
  BondBasedOperator<dim>::BondBasedOperator(const Discretization<dim>      &discretization,
                                            const BondBasedModelParameters &p)
    : disc(discretization)
    , linearized(p.linearized)
  {
    const double delta = disc.parameters().delta;
    c = p.micromodulus > 0. ?
          p.micromodulus :
          bond_based_micromodulus(dim, p.omega, delta, p.youngs_modulus, p.plane_stress);
    s0 = p.critical_stretch > 0. ? p.critical_stretch :
         p.fracture_energy > 0.  ? bond_based_critical_stretch(dim, p.omega, delta, c,
                                                               p.fracture_energy) :
                                   std::numeric_limits<double>::infinity();

    const auto &nb = disc.neighborhood;
    // omega at min(r, delta): bonds of the partial-volume shell beyond delta
    // keep the horizon value, weighted by beta (as in the diffusion model).
    // Stored divided by |xi|: the bond stiffness ||C(xi)|| beta V_j, which
    // saves a division per bond in compute_forces().
    bond_coefficient.resize(nb.bond_length.size());
    for (std::size_t t = 0; t < bond_coefficient.size(); ++t)
      bond_coefficient[t] = c * influence(p.omega, std::min(nb.bond_length[t], delta), delta) *
                            nb.bond_weight[t] / nb.bond_length[t];

    row_stiffness.resize(disc.n_owned());
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        double s = 0.;
        for (std::uint64_t k = 0; k < nb.row_start[i + 1] - nb.row_start[i]; ++k)
          s += bond_coefficient[nb.table_start[i] + k];
        row_stiffness[i] = s;
      }
    broken_flag.assign(nb.n_bonds(), 0);
    setup_half_list();
    setup_lattice_sweep();
  }

  template <int dim>
  unsigned int
  BondBasedOperator<dim>::box_index(const unsigned int i, const std::uint64_t b) const
  {
    const auto  &li = disc.lattice_index[i];
    const auto  &lj = disc.lattice_index[disc.neighborhood.col[b]];
    const int    W  = 2 * box_radius + 1;
    unsigned int index = 0, stride = 1;
    for (unsigned int d = 0; d < dim; ++d)
      {
        index += (lj[d] - li[d] + box_radius) * stride;
        stride *= W;
      }
    return index;
  }

  template <int dim>
  std::uint64_t
  BondBasedOperator<dim>::mirror_bond(const unsigned int i, const std::uint64_t b) const
  {
    // Row j lists its bonds in increasing box index; the copy of bond b has
    // the negated offset, i.e. the mirrored box index, and lies in j's
    // negative half.
    const auto        &nb     = disc.neighborhood;
    const unsigned int j      = nb.col[b];
    const unsigned int target = centre_index() * 2 - box_index(i, b);
    std::uint64_t      lo = nb.row_start[j], hi = nb.row_start[j] + half_offset[j];
    while (lo < hi)
      {
        const std::uint64_t mid = (lo + hi) / 2;
        if (box_index(j, mid) < target)
          lo = mid + 1;
        else
          hi = mid;
      }
    AssertThrow(lo < nb.row_start[j + 1] && nb.col[lo] == std::int32_t(i),
                ExcInternalError("The copy of a bond is missing in its neighbour's row."));
    return lo;
  }

  template <int dim>
  void
  BondBasedOperator<dim>::setup_half_list()
  {
    const auto  &nb    = disc.neighborhood;
    const double dx    = disc.parameters().dx;
    const double delta = disc.parameters().delta;
    box_radius = int(std::ceil((disc.parameters().partial_volume ? delta + 0.5 * dx : delta) / dx));
    const unsigned int centre = centre_index();

    half_offset.resize(disc.n_owned());
    ghost_row.clear();
    ghost_row_start.assign(1, 0);
    ghost_bond.clear();
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        const std::uint64_t begin = nb.row_start[i], end = nb.row_start[i + 1];
        // Bonds are in increasing box index (stencil order): the positive
        // offsets are a suffix.
        std::uint64_t lo = begin, hi = end;
        while (lo < hi)
          {
            const std::uint64_t mid = (lo + hi) / 2;
            if (box_index(i, mid) < centre)
              lo = mid + 1;
            else
              hi = mid;
          }
        half_offset[i] = lo - begin;
        for (std::uint64_t b = begin; b < lo; ++b)
          if (nb.col[b] >= std::int32_t(disc.n_owned()))
            ghost_bond.push_back(b);
        if (ghost_bond.size() > ghost_row_start.back())
          {
            ghost_row.push_back(i);
            ghost_row_start.push_back(ghost_bond.size());
          }
      }
    ghost_col.resize(ghost_bond.size());
    ghost_stiffness.resize(ghost_bond.size());
    ghost_length.resize(ghost_bond.size());
    ghost_broken.resize(ghost_bond.size());
    for (std::size_t g = 0; g < ghost_row.size(); ++g)
      {
        const unsigned int i = ghost_row[g];
        for (std::uint64_t e = ghost_row_start[g]; e < ghost_row_start[g + 1]; ++e)
          {
            const std::uint64_t t = nb.table_start[i] + ghost_bond[e] - nb.row_start[i];
            ghost_col[e]          = nb.col[ghost_bond[e]];
            ghost_stiffness[e]    = bond_coefficient[t];
            ghost_length[e]       = nb.bond_length[t];
          }
      }

    // Newton's third law needs the same stiffness in both copies of a bond:
    // the table entries of opposite stencil offsets (slots s and S-1-s).
    const unsigned int S = nb.stencil_size;
    for (unsigned int t = 0; t < S / 2; ++t)
      AssertThrow(bond_coefficient[t] == bond_coefficient[S - 1 - t] &&
                    nb.bond_length[t] == nb.bond_length[S - 1 - t],
                  ExcInternalError("The bond stencil is not symmetric."));
  }

  template <int dim>
  std::uint64_t
  BondBasedOperator<dim>::find_sweep_bond(const unsigned int i,
                                          const unsigned int h,
                                          const bool         upper,
                                          const std::int32_t partner) const
  {
    const auto        &nb = disc.neighborhood;
    const unsigned int S  = nb.stencil_size;
    std::uint64_t      b  = nb.row_start[i];
    const std::uint64_t end = nb.row_start[i + 1];
    if (nb.table_start[i] == 0 && end - b == S && sweep_slot[h] < S)
      b += upper ? S - 1 - sweep_slot[h] : sweep_slot[h];
    else
      {
        // Another row: the bond's column is the partner (once per row). A
        // scan of the contiguous columns, not a binary search over the box
        // index, whose every probe loads a neighbour's lattice index (in the
        // breaking steps that search was ~10 % of the step time).
#ifdef PERIDEAL_PMB_AVX512
        const __m512i key = _mm512_set1_epi32(partner);
        for (; b + 16 <= end; b += 16)
          if (const __mmask16 hit = _mm512_cmpeq_epi32_mask(
                _mm512_loadu_si512(static_cast<const void *>(nb.col.data() + b)), key))
            {
              b += __builtin_ctz(hit);
              break;
            }
#endif
        while (b < end && nb.col[b] != partner)
          ++b;
        AssertThrow(b < end, ExcInternalError("A bond of the lattice sweep is missing in its row."));
      }
    Assert(nb.col[b] == partner &&
             box_index(i, b) ==
               (upper ? 2 * centre_index() - sweep_box_index[h] : sweep_box_index[h]),
           ExcInternalError());
    return b;
  }

  template <int dim>
  void
  BondBasedOperator<dim>::set_lattice_sweep_chunk(const unsigned int n)
  {
    check_parameter(n >= 8 && n <= max_sweep_chunk && n % 8 == 0, "Lattice sweep chunk", n,
                    "a multiple of 8 in [8, " + std::to_string(max_sweep_chunk) + "]");
    sweep_chunk = n;
  }

  template <int dim>
  void
  BondBasedOperator<dim>::set_lattice_sweep_offsets_per_pass(const unsigned int k)
  {
    check_parameter(k >= 1 && k <= 4, "Lattice sweep offsets per pass", k, "1, 2, 3 or 4");
    sweep_offsets_per_pass = k;
    set_sweep_bit_slots();
  }

  template <int dim>
  void
  BondBasedOperator<dim>::set_lattice_sweep_pairs(const bool use_pairs)
  {
    sweep_pairs = use_pairs;
    set_sweep_bit_slots();
  }

  template <int dim>
  void
  BondBasedOperator<dim>::set_sweep_bit_slots()
  {
    const unsigned int H = sweep_offset.size(), K = sweep_offsets_per_pass;
    sweep_pass.clear();
    sweep_pass_offset.clear();
    sweep_pair_delta = 0;
    // Paired passes (3D, four pairs per pass): offsets o and o + D, D the
    // smallest of 1, 2, 4 box rows that is a whole number of groups of
    // eight positions (sweep_offset is increasing).
    std::vector<unsigned int> first, second, single;
    if (dim == 3 && K == 4 && sweep_pairs)
      for (const std::int64_t m : {1, 2, 4})
        if (m * sweep_stride[1 % dim] % 8 == 0)
          {
            sweep_pair_delta = m * sweep_stride[1 % dim];
            break;
          }
    std::vector<bool> paired(H, false);
    if (sweep_pair_delta > 0)
      for (unsigned int h = 0; h < H; ++h)
        if (!paired[h])
          {
            const auto it = std::lower_bound(sweep_offset.begin(), sweep_offset.end(),
                                             sweep_offset[h] + sweep_pair_delta);
            const unsigned int h2 = it - sweep_offset.begin();
            if (it != sweep_offset.end() && *it == sweep_offset[h] + sweep_pair_delta && !paired[h2])
              {
                first.push_back(h);
                second.push_back(h2);
                paired[h] = paired[h2] = true;
              }
          }
    for (unsigned int h = 0; h < H; ++h)
      if (!paired[h])
        single.push_back(h);
    // A pass takes the pairs (or offsets) q, q + G, q + 2G, ... of its list
    // (G = its length / K rounded up for pairs, down for single offsets),
    // which lie in different lattice lines: the reactions of one pass are
    // more than 8 apart, so no store partially overlaps the next load.
    const unsigned int P = first.size(), GP = (P + K - 1) / K;
    for (unsigned int g = 0; g < GP; ++g)
      {
        const unsigned int start = sweep_pass_offset.size();
        for (const auto *list : {&first, &second})
          for (unsigned int q = g; q < P; q += GP)
            sweep_pass_offset.push_back((*list)[q]);
        sweep_pass.push_back({{start, (unsigned int)(sweep_pass_offset.size() - start) / 2, 1}});
      }
    const unsigned int S = single.size(), G = S / K;
    for (unsigned int g = 0; g < G; ++g)
      {
        sweep_pass.push_back({{(unsigned int)sweep_pass_offset.size(), K, 0}});
        for (unsigned int q = 0; q < K; ++q)
          sweep_pass_offset.push_back(single[g + q * G]);
      }
    for (unsigned int q = K * G; q < S; ++q)
      {
        sweep_pass.push_back({{(unsigned int)sweep_pass_offset.size(), 1, 0}});
        sweep_pass_offset.push_back(single[q]);
      }
    // The offsets of a pass get adjacent bit slots, in pass order; the byte
    // row of a group has H slots rounded up to a multiple of 8.
    std::vector<unsigned int> slot(H);
    for (unsigned int i = 0; i < sweep_pass_offset.size(); ++i)
      slot[sweep_pass_offset[i]] = i;
    if (slot != sweep_bit_slot)
      {
        sweep_bit_slot   = slot;
        sweep_bits_valid = false;
      }
    sweep_bit_row = (H + 7) / 8 * 8;
  }

  template <int dim>
  bool
  BondBasedOperator<dim>::lattice_sweep_compiled()
  {
#ifdef PERIDEAL_PMB_AVX512
    return dim > 1;
#else
    return false;
#endif
  }

  template <int dim>
  void
  BondBasedOperator<dim>::setup_lattice_sweep()
  {
    sweep_available = false;
#ifdef PERIDEAL_PMB_AVX512
    const auto        &nb      = disc.neighborhood;
    const std::size_t  n_local = disc.position.size();
    const unsigned int n_owned = disc.n_owned();
    if (dim == 1 || linearized || n_owned == 0 || disc.lattice_index.size() != n_local)
      return;
    // The box of the local lattice positions; every extent at least 2M+1 so
    // that a lexicographically positive offset has a positive linear offset.
    std::array<int, dim> upper;
    for (unsigned int d = 0; d < dim; ++d)
      {
        sweep_lower[d] = std::numeric_limits<int>::max();
        upper[d]       = std::numeric_limits<int>::min();
      }
    for (const auto &li : disc.lattice_index)
      for (unsigned int d = 0; d < dim; ++d)
        {
          sweep_lower[d] = std::min(sweep_lower[d], li[d]);
          upper[d]       = std::max(upper[d], li[d]);
        }
    std::int64_t n_box = 1;
    for (unsigned int d = 0; d < dim; ++d)
      {
        sweep_stride[d] = n_box;
        n_box *= std::max<std::int64_t>(upper[d] - sweep_lower[d] + 1, 2 * box_radius + 1);
      }
    if (n_box > 8 * std::int64_t(n_local) + 4096 || n_box > (std::int64_t(1) << 30))
      return;

    // The positive stencil offsets (box index above the centre).
    const int          W      = 2 * box_radius + 1;
    const unsigned int centre = centre_index();
    sweep_half_of_box.assign(2 * centre + 1, -1);
    sweep_offset.clear();
    sweep_box_index.clear();
    for (unsigned int q = centre + 1; q <= 2 * centre; ++q)
      {
        std::int64_t o = 0;
        unsigned int rest = q;
        for (unsigned int d = 0; d < dim; ++d)
          {
            o += std::int64_t(int(rest % W) - box_radius) * sweep_stride[d];
            rest /= W;
          }
        Assert(o > 0, ExcInternalError());
        sweep_half_of_box[q] = sweep_half_of_box[2 * centre - q] = sweep_offset.size();
        sweep_offset.push_back(o);
        sweep_box_index.push_back(q);
      }
    const std::size_t n_half = sweep_offset.size();
    sweep_slot.assign(n_half, std::numeric_limits<unsigned int>::max());
    sweep_k.assign(n_half, std::numeric_limits<double>::quiet_NaN());
    sweep_r.assign(n_half, std::numeric_limits<double>::quiet_NaN());

    // Every bond of an offset must have the same stiffness and length (and
    // both copies of a bond the same: the offset and its negation share h).
    std::vector<bool> seen(n_half, false);
    const auto        uniform = [&](const unsigned int h, const std::uint64_t t) {
      if (!seen[h])
        {
          seen[h]    = true;
          sweep_k[h] = bond_coefficient[t];
          sweep_r[h] = nb.bond_length[t];
          return true;
        }
      return sweep_k[h] == bond_coefficient[t] && sweep_r[h] == nb.bond_length[t];
    };
    // Regular rows share the stencil table: check its slots once.
    std::vector<bool> table_checked;
    for (unsigned int i = 0; i < n_owned; ++i)
      {
        const std::uint64_t begin = nb.row_start[i], n = nb.row_start[i + 1] - begin;
        const bool regular = nb.table_start[i] == 0 && n == nb.stencil_size;
        if (regular && !table_checked.empty())
          continue;
        for (std::uint64_t k = 0; k < n; ++k)
          {
            const unsigned int q = box_index(i, begin + k);
            if (q == centre || !uniform(sweep_half_of_box[q], nb.table_start[i] + k))
              return;
          }
        if (regular)
          {
            if (table_checked.empty())
              for (std::uint64_t k = 0; k < n; ++k)
                {
                  const unsigned int q = box_index(i, begin + k);
                  if (q > centre)
                    sweep_slot[sweep_half_of_box[q]] = k;
                }
            table_checked.assign(1, true);
          }
      }

    // Keep only the offsets that occur in a row: the half of the stencil's
    // bounding box also holds offsets beyond the horizon (3D m = 3 with
    // partial volumes: 364, of which 89 are bonds), and a pass over those
    // would only read zero bits (and dilute the passes of live offsets).
    {
      std::vector<int> live_index(n_half, -1);
      unsigned int     n_live = 0;
      for (unsigned int h = 0; h < n_half; ++h)
        if (seen[h])
          {
            live_index[h] = n_live;
            sweep_offset[n_live]    = sweep_offset[h];
            sweep_box_index[n_live] = sweep_box_index[h];
            sweep_slot[n_live]      = sweep_slot[h];
            sweep_k[n_live]         = sweep_k[h];
            sweep_r[n_live]         = sweep_r[h];
            ++n_live;
          }
      if (n_live == 0)
        return;
      sweep_offset.resize(n_live);
      sweep_box_index.resize(n_live);
      sweep_slot.resize(n_live);
      sweep_k.resize(n_live);
      sweep_r.resize(n_live);
      for (int &h : sweep_half_of_box)
        if (h >= 0)
          h = live_index[h];
    }

    // Offsets per pass: in 3D four (1.04-1.11x two in interleaved CPU-time
    // runs of 3D m = 3, doc/benchmarks.md); in 2D two (four measured the
    // same), which keeps the 2D summation order of the two-grid solver's
    // copy of the sweep.
    sweep_offsets_per_pass = dim == 3 ? 4 : 2;
    set_sweep_bit_slots();
    sweep_n_box   = n_box;
    sweep_n_bytes = (sweep_n_box + 7) / 8;
    // Padding: the neighbour streams read up to the largest offset plus one
    // vector past the last box position.
    // The component stride is a multiple of 8 (64-byte aligned components)
    // with 8 N = 1344 mod 4096: the dim arrays of positions (page offset 0)
    // and reactions (2048) then start at page offsets at least 640 bytes
    // apart (0, 1344, 2688 and 2048, 3392, 640), so that the reaction store
    // of one component is not 4K-aliased with the next component's loads.
    sweep_n_alloc = 8 * sweep_n_bytes + sweep_offset.back() + 16;
    sweep_n_alloc = (sweep_n_alloc + 511 - 168) / 512 * 512 + 168;
    internal::LatticeSweep::map_box_positions<dim>(
      disc.lattice_index, sweep_lower, sweep_stride, sweep_n_box, sweep_position, sweep_node);
    sweep_p.assign(dim * sweep_n_alloc, 0.);
    sweep_reaction.assign(dim * sweep_n_alloc, 0.);
    sweep_bits_valid = false;
    sweep_available  = true;
#endif
  }

  template <int dim>
  void
  BondBasedOperator<dim>::build_sweep_bits()
  {
    const auto        &nb     = disc.neighborhood;
    const unsigned int centre = centre_index();
    sweep_live.assign(sweep_bit_row * sweep_n_bytes, 0);
    // The lower end of a bond (from which its offset is positive) and its
    // offset; the bit is set by either owned copy and cleared if either
    // copy is broken.
    const auto bit = [&](const unsigned int i, const std::uint64_t b, std::size_t &byte) {
      const unsigned int q = box_index(i, b);
      const unsigned int h = sweep_half_of_box[q];
      const std::uint32_t L = q > centre ? sweep_position[i] : sweep_position[nb.col[b]];
      byte = sweep_bit_slot[h] + std::size_t(L / 8) * sweep_bit_row;
      return std::uint8_t(1u << (L % 8));
    };
    for (int pass = 0; pass < 2; ++pass)
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        for (std::uint64_t b = nb.row_start[i]; b < nb.row_start[i + 1]; ++b)
          if ((pass == 0) == (broken_flag[b] == 0))
            {
              std::size_t        byte;
              const std::uint8_t m = bit(i, b, byte);
              if (pass == 0)
                sweep_live[byte] |= m;
              else
                sweep_live[byte] &= std::uint8_t(~m);
            }
    sweep_bits_valid = true;
  }

  template <int dim>
  void
  BondBasedOperator<dim>::initialize(VectorField &field) const
  {
    for (auto &v : field)
      disc.initialize_vector(v);
  }

  namespace
  {
    /**
     * Doubles per node in the deformed-position records of compute_forces():
     * dim, padded to 4 in 3D so that a record is one aligned 32-byte load.
     */
    template <int dim>
    constexpr unsigned int record_size = dim == 3 ? 4 : dim;

    /**
     * Doubles per node in the scratch of compute_forces(): the deformed
     * position record, then the force record of the half list. A bond's
     * neighbour load and its reaction update touch the same cache line
     * (3D: one 64-byte line per node).
     */
    template <int dim>
    constexpr unsigned int node_stride = 2 * record_size<dim>;

    /**
     * One row of the nonlinear PMB force, portable version. p holds the
     * deformed positions x - x_c + u (records of record_size<dim>
     * doubles), k the bond stiffnesses c omega beta V / |xi| and r the
     * lengths |xi| of the row's table slice. With l = |y|, y = p_j - p_i,
     * the force is k (l - r) y / l, i.e. c omega s beta V y / l with the
     * stretch s = (l - r)/r (3.1); the bond breaks when l - r > s0 r, i.e.
     * s > s0 (2.34). The two copies of a bond evaluate the same
     * correctly rounded expressions of y and -y (and the same table
     * values), so they see the same l and break together.
     */
    /**
     * Where a half row sends the reaction of its bonds: the force records of
     * all local nodes (subtract from the neighbour's record), and the list of
     * newly broken bonds whose copy in an owned neighbour's row must be
     * flagged too. A full row (Scatter = false) uses neither.
     */
    struct Reaction
    {
      double                     *force   = nullptr;
      std::int32_t                n_owned = 0;
      std::uint64_t               first_bond = 0; ///< CSR index of the row slice's bond 0
      std::vector<std::uint64_t> *newly_broken = nullptr;
      bool                       *broke = nullptr; ///< set when a bond breaks (if not null)
    };

    /**
     * One row of the nonlinear PMB force, portable version. p holds the
     * deformed positions x - x_c + u (records of record_size<dim>
     * doubles), k the bond stiffnesses c omega beta V / |xi| and r the
     * lengths |xi| of the row's table slice. With l = |y|, y = p_j - p_i,
     * the force is k (l - r) y / l, i.e. c omega s beta V y / l with the
     * stretch s = (l - r)/r (3.1); the bond breaks when l - r > s0 r, i.e.
     * s > s0 (2.34). The two copies of a bond evaluate the same
     * correctly rounded expressions of y and -y (and the same table
     * values), so they see the same l and break together. With Scatter,
     * -k (l - r) y / l goes to the neighbour's force record (half list).
     */
    template <int dim, bool Scatter>
    inline void
    pmb_row(const double       *p,
            const double       *pi,
            const std::int32_t *col,
            const double       *k,
            const double       *r,
            std::uint8_t       *broken,
            const unsigned int  n,
            const double        s0,
            double             *f,
            const Reaction     &reaction)
    {
      for (unsigned int b = 0; b < n; ++b)
        {
          if (broken[b])
            continue;
          const double *pj = p + std::size_t(node_stride<dim>) * col[b];
          double        y[dim];
          for (unsigned int d = 0; d < dim; ++d)
            y[d] = pj[d] - pi[d];
          double l2 = y[0] * y[0];
          for (unsigned int d = 1; d < dim; ++d)
            l2 = std::fma(y[d], y[d], l2);
          const double l  = std::sqrt(l2);
          const double dl = l - r[b];
          if (dl > s0 * r[b])
            {
              broken[b] = 1;
              if (reaction.broke)
                *reaction.broke = true;
              if (Scatter && col[b] < reaction.n_owned)
                reaction.newly_broken->push_back(reaction.first_bond + b);
              continue;
            }
          const double scale = k[b] * dl / l;
          for (unsigned int d = 0; d < dim; ++d)
            {
              const double t = scale * y[d];
              f[d] += t;
              if constexpr (Scatter)
                reaction.force[std::size_t(node_stride<dim>) * col[b] + d] -= t;
            }
        }
    }

#ifdef PERIDEAL_PMB_AVX512
    /**
     * y_j - p_i for the eight bonds b..b+7 of a row as dim vectors: each
     * bond loads its neighbour's record (16 B in 2D, 32 B in 3D) and the
     * records are transposed in registers. This is faster than zmm gathers
     * on AMD Zen (doc/benchmarks.md). Lanes past the row end read the
     * row's own record.
     */
    template <int dim>
    inline void
    load_bond_vectors(const double       *p,
                      const double       *pi,
                      const std::int32_t *col,
                      const unsigned int  b,
                      const unsigned int  n,
                      __m512d            *y)
    {
      const double *rec[8];
      if (b + 8 <= n)
        for (unsigned int q = 0; q < 8; ++q)
          rec[q] = p + std::size_t(node_stride<dim>) * col[b + q];
      else
        for (unsigned int q = 0; q < 8; ++q)
          rec[q] = b + q < n ? p + std::size_t(node_stride<dim>) * col[b + q] : pi;
      if constexpr (dim == 2)
        {
          __m512d lo = _mm512_castpd128_pd512(_mm_loadu_pd(rec[0]));
          __m512d hi = _mm512_castpd128_pd512(_mm_loadu_pd(rec[4]));
          lo         = _mm512_insertf64x2(lo, _mm_loadu_pd(rec[1]), 1);
          hi         = _mm512_insertf64x2(hi, _mm_loadu_pd(rec[5]), 1);
          lo         = _mm512_insertf64x2(lo, _mm_loadu_pd(rec[2]), 2);
          hi         = _mm512_insertf64x2(hi, _mm_loadu_pd(rec[6]), 2);
          lo         = _mm512_insertf64x2(lo, _mm_loadu_pd(rec[3]), 3);
          hi         = _mm512_insertf64x2(hi, _mm_loadu_pd(rec[7]), 3);
          y[0] = _mm512_permutex2var_pd(lo, _mm512_setr_epi64(0, 2, 4, 6, 8, 10, 12, 14), hi);
          y[1] = _mm512_permutex2var_pd(lo, _mm512_setr_epi64(1, 3, 5, 7, 9, 11, 13, 15), hi);
        }
      else
        {
          __m512d v[4];
          for (unsigned int q = 0; q < 4; ++q)
            v[q] = _mm512_insertf64x4(_mm512_castpd256_pd512(_mm256_loadu_pd(rec[2 * q])),
                                      _mm256_loadu_pd(rec[2 * q + 1]), 1);
          const __m512i ixy = _mm512_setr_epi64(0, 4, 8, 12, 1, 5, 9, 13);
          const __m512i iz  = _mm512_setr_epi64(2, 6, 10, 14, 2, 6, 10, 14);
          const __m512d xy0 = _mm512_permutex2var_pd(v[0], ixy, v[1]);
          const __m512d xy1 = _mm512_permutex2var_pd(v[2], ixy, v[3]);
          const __m512d z0  = _mm512_permutex2var_pd(v[0], iz, v[1]);
          const __m512d z1  = _mm512_permutex2var_pd(v[2], iz, v[3]);
          y[0]              = _mm512_shuffle_f64x2(xy0, xy1, 0x44);
          y[1]              = _mm512_shuffle_f64x2(xy0, xy1, 0xEE);
          y[2]              = _mm512_shuffle_f64x2(z0, z1, 0x44);
        }
      for (unsigned int d = 0; d < dim; ++d)
        y[d] = _mm512_sub_pd(y[d], _mm512_set1_pd(pi[d]));
    }

    /**
     * Subtract the eight dim vectors t (lane q: bond b+q) from the force
     * records of the bonds' neighbours: the inverse of the transpose in
     * load_bond_vectors(), then one 16/32-byte read-modify-write per bond.
     * The columns of a row are distinct, so the lanes never collide.
     */
    template <int dim>
    inline void
    scatter_bond_vectors(double             *F,
                         const std::int32_t *col,
                         const unsigned int  n_lanes,
                         const __m512d      *t)
    {
      constexpr unsigned int R = node_stride<dim>;
      if constexpr (dim == 2)
        {
          const __m512d lo = _mm512_unpacklo_pd(t[0], t[1]); // x0 y0 x2 y2 x4 y4 x6 y6
          const __m512d hi = _mm512_unpackhi_pd(t[0], t[1]); // x1 y1 x3 y3 ...
          const __m128d v[8] = {_mm512_castpd512_pd128(lo),   _mm512_castpd512_pd128(hi),
                                _mm512_extractf64x2_pd(lo, 1), _mm512_extractf64x2_pd(hi, 1),
                                _mm512_extractf64x2_pd(lo, 2), _mm512_extractf64x2_pd(hi, 2),
                                _mm512_extractf64x2_pd(lo, 3), _mm512_extractf64x2_pd(hi, 3)};
          for (unsigned int q = 0; q < n_lanes; ++q)
            {
              double *dst = F + std::size_t(R) * col[q];
              _mm_storeu_pd(dst, _mm_sub_pd(_mm_loadu_pd(dst), v[q]));
            }
        }
      else
        {
          const __m512d zero = _mm512_setzero_pd();
          const __m512d lo   = _mm512_unpacklo_pd(t[0], t[1]);
          const __m512d hi   = _mm512_unpackhi_pd(t[0], t[1]);
          const __m512d zlo  = _mm512_unpacklo_pd(t[2], zero); // z0 0 z2 0 ...
          const __m512d zhi  = _mm512_unpackhi_pd(t[2], zero);
          const __m512i a    = _mm512_setr_epi64(0, 1, 8, 9, 2, 3, 10, 11);
          const __m512i c    = _mm512_setr_epi64(4, 5, 12, 13, 6, 7, 14, 15);
          const __m512d r02  = _mm512_permutex2var_pd(lo, a, zlo);
          const __m512d r46  = _mm512_permutex2var_pd(lo, c, zlo);
          const __m512d r13  = _mm512_permutex2var_pd(hi, a, zhi);
          const __m512d r57  = _mm512_permutex2var_pd(hi, c, zhi);
          const __m256d v[8] = {_mm512_castpd512_pd256(r02),    _mm512_castpd512_pd256(r13),
                                _mm512_extractf64x4_pd(r02, 1), _mm512_extractf64x4_pd(r13, 1),
                                _mm512_castpd512_pd256(r46),    _mm512_castpd512_pd256(r57),
                                _mm512_extractf64x4_pd(r46, 1), _mm512_extractf64x4_pd(r57, 1)};
          for (unsigned int q = 0; q < n_lanes; ++q)
            {
              double *dst = F + std::size_t(R) * col[q];
              _mm256_storeu_pd(dst, _mm256_sub_pd(_mm256_loadu_pd(dst), v[q]));
            }
        }
    }

    using internal::LatticeSweep::pmb_bond_scale;

    /**
     * pmb_row() with AVX-512, eight bonds per iteration and a masked tail,
     * one accumulator per component reduced once per row. Every bond goes
     * through the same instructions (pmb_bond_scale: 1/l from vrsqrt14pd
     * and one fourth-order refinement, a few ulp from 1/sqrt),
     * so the two copies of a bond, and the half-list and ghost-list
     * evaluations of a bond on different ranks, see bitwise the same l and
     * break together.
     */
    template <int dim, bool Scatter>
    inline void
    pmb_row_avx512(const double       *p,
                   const double       *pi,
                   const std::int32_t *col,
                   const double       *k,
                   const double       *r,
                   std::uint8_t       *broken,
                   const unsigned int  n,
                   const double        s0,
                   double             *f,
                   const Reaction     &reaction)
    {
      __m512d acc[dim];
      for (unsigned int d = 0; d < dim; ++d)
        acc[d] = _mm512_setzero_pd();
      const __m512d vs0 = _mm512_set1_pd(s0);
      for (unsigned int b = 0; b < n; b += 8)
        {
          const __mmask8 m = n - b >= 8 ? __mmask8(0xFF) : __mmask8((1u << (n - b)) - 1u);
          const __mmask8 alive =
            _mm_mask_cmpeq_epi8_mask(m, _mm_maskz_loadu_epi8(m, broken + b), _mm_setzero_si128());
          if (alive == 0)
            continue;
          __m512d y[dim];
          load_bond_vectors<dim>(p, pi, col, b, n, y);
          __m512d l2 = _mm512_mul_pd(y[0], y[0]);
          for (unsigned int d = 1; d < dim; ++d)
            l2 = _mm512_fmadd_pd(y[d], y[d], l2);
          __mmask8      brk;
          const __m512d rb = _mm512_maskz_loadu_pd(alive, r + b);
          const __m512d scale =
            pmb_bond_scale(l2, alive, rb, _mm512_maskz_loadu_pd(alive, k + b),
                           _mm512_mul_pd(vs0, rb), brk);
          if constexpr (Scatter)
            {
              __m512d t[dim];
              for (unsigned int d = 0; d < dim; ++d)
                {
                  t[d]   = _mm512_mul_pd(scale, y[d]);
                  acc[d] = _mm512_add_pd(acc[d], t[d]);
                }
              scatter_bond_vectors<dim>(reaction.force, col + b, std::min(8u, n - b), t);
            }
          else
            for (unsigned int d = 0; d < dim; ++d)
              acc[d] = _mm512_fmadd_pd(scale, y[d], acc[d]);
          if (brk)
            {
              _mm_mask_storeu_epi8(broken + b, brk, _mm_set1_epi8(1));
              if (reaction.broke)
                *reaction.broke = true;
              if constexpr (Scatter)
                for (unsigned int q = 0; q < 8; ++q)
                  if ((brk >> q) & 1u && col[b + q] < reaction.n_owned)
                    reaction.newly_broken->push_back(reaction.first_bond + b + q);
            }
        }
      for (unsigned int d = 0; d < dim; ++d)
        f[d] = _mm512_reduce_add_pd(acc[d]);
    }
#endif
  } // namespace

  namespace
  {
    /** One row by the AVX-512 kernel where available, else the portable one. */
    template <int dim, bool Scatter>
    inline void
    pmb_row_dispatch(const double       *p,
                     const double       *pi,
                     const std::int32_t *col,
                     const double       *k,
                     const double       *r,
                     std::uint8_t       *broken,
                     const unsigned int  n,
                     const double        s0,
                     double             *f,
                     const Reaction     &reaction)
    {
#ifdef PERIDEAL_PMB_AVX512
      if constexpr (dim > 1)
        pmb_row_avx512<dim, Scatter>(p, pi, col, k, r, broken, n, s0, f, reaction);
      else
#endif
        pmb_row<dim, Scatter>(p, pi, col, k, r, broken, n, s0, f, reaction);
    }
  } // namespace

  template <int dim>
  void
  BondBasedOperator<dim>::full_list_forces(VectorField &force)
  {
    const auto    &nb = disc.neighborhood;
    const double  *p  = deformed.data();
    constexpr auto R  = node_stride<dim>;
    bool           broke = false;
    Reaction       reaction;
    reaction.broke = &broke;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        const std::uint64_t begin  = nb.row_start[i];
        double              f[dim] = {};
        pmb_row_dispatch<dim, false>(p, p + std::size_t(R) * i, nb.col.data() + begin,
                                     bond_coefficient.data() + nb.table_start[i],
                                     nb.bond_length.data() + nb.table_start[i],
                                     broken_flag.data() + begin, nb.row_start[i + 1] - begin, s0,
                                     f, reaction);
        for (unsigned int d = 0; d < dim; ++d)
          force[d].local_element(i) = f[d];
      }
    // The list loops change broken_flag without the sweep's bits.
    if (broke)
      sweep_bits_valid = false;
  }

  template <int dim>
  void
  BondBasedOperator<dim>::half_list_forces(VectorField &force)
  {
    const auto        &nb      = disc.neighborhood;
    const double      *p       = deformed.data();
    const unsigned int n_owned = disc.n_owned();
    constexpr auto     R       = node_stride<dim>;
    // Force records of all local nodes, interleaved with the positions: the
    // reactions to ghost nodes land in the ghost records and are dropped
    // (the ghost's owner evaluates the bond itself, from its ghost list).
    double *F = deformed.data() + record_size<dim>;
    newly_broken.clear();
    Reaction reaction;
    reaction.force        = F;
    reaction.n_owned      = n_owned;
    reaction.newly_broken = &newly_broken;
    bool broke            = false;
    reaction.broke        = &broke;
    for (unsigned int i = 0; i < n_owned; ++i)
      {
        const std::uint64_t h = nb.row_start[i] + half_offset[i];
        const std::uint64_t t = nb.table_start[i] + half_offset[i];
        reaction.first_bond   = h;
        double f[dim]         = {};
        pmb_row_dispatch<dim, true>(p, p + std::size_t(R) * i, nb.col.data() + h,
                                    bond_coefficient.data() + t, nb.bond_length.data() + t,
                                    broken_flag.data() + h, nb.row_start[i + 1] - h, s0, f,
                                    reaction);
        for (unsigned int d = 0; d < dim; ++d)
          F[R * i + d] += f[d];
      }
    // Negative-offset bonds to ghosts, from the owned end only.
    for (std::size_t e = 0; e < ghost_bond.size(); ++e)
      ghost_broken[e] = broken_flag[ghost_bond[e]];
    Reaction ghost_reaction;
    ghost_reaction.broke = &broke;
    for (std::size_t g = 0; g < ghost_row.size(); ++g)
      {
        const unsigned int  i = ghost_row[g];
        const std::uint64_t e = ghost_row_start[g];
        double              f[dim] = {};
        pmb_row_dispatch<dim, false>(p, p + std::size_t(R) * i, ghost_col.data() + e,
                                     ghost_stiffness.data() + e, ghost_length.data() + e,
                                     ghost_broken.data() + e, ghost_row_start[g + 1] - e, s0, f,
                                     ghost_reaction);
        for (unsigned int d = 0; d < dim; ++d)
          F[R * i + d] += f[d];
      }
    for (std::size_t e = 0; e < ghost_bond.size(); ++e)
      broken_flag[ghost_bond[e]] = ghost_broken[e];
    // A bond between owned nodes broke in its half row: flag its other copy.
    for (const std::uint64_t b : newly_broken)
      {
        const auto row = std::upper_bound(nb.row_start.begin(), nb.row_start.end(), b) -
                         nb.row_start.begin() - 1;
        broken_flag[mirror_bond(row, b)] = 1;
      }
    for (unsigned int d = 0; d < dim; ++d)
      {
        double *fd = force[d].begin();
        for (unsigned int i = 0; i < n_owned; ++i)
          fd[i] = F[R * i + d];
      }
    if (broke)
      sweep_bits_valid = false;
  }

  template <int dim>
  Point<dim>
  BondBasedOperator<dim>::deformation_origin() const
  {
    std::array<int, dim> mid;
    for (unsigned int d = 0; d < dim; ++d)
      mid[d] = int(disc.lattice_size()[d] / 2);
    return disc.lattice_point(mid);
  }

  template <int dim>
  void
  BondBasedOperator<dim>::sweep_forces(const VectorField &u, VectorField &force)
  {
    const std::vector<Point<dim>> &x       = disc.position;
    const unsigned int             n_owned = disc.n_owned();
    const std::size_t              N       = sweep_n_alloc;
    // Deformed positions x - x_c + u as in the list loops (bitwise the same
    // values), one array per component over the box.
    const Point<dim> xc = deformation_origin();
    for (unsigned int d = 0; d < dim; ++d)
      {
        double       *pd = sweep_p.data() + d * N;
        const double *ud = u[d].begin();
        for (std::size_t i = 0; i < x.size(); ++i)
          pd[sweep_position[i]] = (x[i][d] - xc[d]) + ud[i];
      }
    lattice_sweep_forces(sweep_p.data(), [&](const std::size_t  c0,
                                             const unsigned int   n,
                                             const double        *f,
                                             const unsigned int   C) {
      const std::size_t c1 = std::min<std::size_t>(c0 + n, sweep_n_box);
      for (std::size_t L = c0; L < c1; ++L)
        {
          const std::int32_t i = sweep_node[L];
          if (i >= 0 && i < std::int32_t(n_owned))
            for (unsigned int d = 0; d < dim; ++d)
              force[d].local_element(i) = f[d * C + L - c0];
        }
    });
  }

  template <int dim>
  void
  BondBasedOperator<dim>::lattice_sweep_forces(const double *p, const SweepChunkFinish &finish)
  {
#ifdef PERIDEAL_PMB_AVX512
    AssertThrow(uses_lattice_sweep(), ExcMessage("The lattice sweep is not in use."));
    if (!sweep_bits_valid)
      build_sweep_bits();
    const unsigned int n_owned = disc.n_owned();
    const std::size_t  N       = sweep_n_alloc;
    sweep_broken.clear();
    // Chunks of C box positions, all offsets per chunk: the chunk's
    // positions, forces and the reactions it reaches (up to the largest
    // offset beyond it) stay in L2. A position's force is final once its
    // chunk is done (reactions come from lower positions only). The
    // reaction array is zero between calls: each chunk clears what it
    // consumed (no separate memset pass).
    const unsigned int C = sweep_chunk;
    alignas(64) double a[dim * max_sweep_chunk];
    const std::size_t      n_bits = 8 * sweep_n_bytes;
    double                *R      = sweep_reaction.data();
    for (std::size_t c0 = 0; c0 < n_bits; c0 += C)
      {
        const unsigned int n = std::min<std::size_t>(C, n_bits - c0);
        std::fill(a, a + dim * C, 0.);
        // The passes of set_sweep_bit_slots(): K offsets each (shared p_L
        // loads and force updates), or K pairs (also shared reactions).
        const internal::LatticeSweep::LiveBits bits{
          sweep_live.data(), 1, sweep_bit_row, sweep_bit_slot.data()};
        const auto plain = [&](auto no, const unsigned int *hs, const std::size_t first,
                               const unsigned int n_groups) {
          internal::LatticeSweep::sweep_offsets<dim, decltype(no)::value>(
            p, R, a + (first - c0), bits, N, C, first, nullptr, n_groups, sweep_offset.data(), hs,
            sweep_k.data(), sweep_r.data(), s0, sweep_broken);
        };
        const auto pass = [&](auto no, const unsigned int *hs, const bool paired) {
          const unsigned int n_groups = n / 8;
          if (!paired)
            {
              plain(no, hs, c0, n_groups);
              return;
            }
          // First offsets from the groups below D / 8 alone, then both, then
          // the second offsets from the last D / 8 groups alone.
          const unsigned int dg = sweep_pair_delta / 8, edge = std::min(dg, n_groups);
          plain(no, hs, c0, edge);
          if (dg < n_groups)
            internal::LatticeSweep::sweep_offset_pairs<dim, decltype(no)::value>(
              p, R, a, bits, N, C, c0, dg, n_groups, sweep_offset.data(), hs, sweep_pair_delta,
              sweep_k.data(), sweep_r.data(), s0, sweep_broken);
          plain(no, hs + decltype(no)::value, c0 + 8 * (n_groups - edge), edge);
        };
        for (const auto &[first, K, paired] : sweep_pass)
          {
            const unsigned int *hs = sweep_pass_offset.data() + first;
            switch (K)
              {
                case 1:
                  pass(std::integral_constant<int, 1>(), hs, paired);
                  break;
                case 2:
                  pass(std::integral_constant<int, 2>(), hs, paired);
                  break;
                case 3:
                  pass(std::integral_constant<int, 3>(), hs, paired);
                  break;
                default:
                  pass(std::integral_constant<int, 4>(), hs, paired);
              }
          }
        for (unsigned int d = 0; d < dim; ++d)
          {
            double *__restrict ad = a + d * C, *__restrict Rd = R + d * N + c0;
#pragma omp simd
            for (unsigned int k = 0; k < n; ++k)
              {
                ad[k] -= Rd[k];
                Rd[k] = 0.;
              }
          }
        finish(c0, n, a, C);
      }
    // Reactions that landed beyond the last chunk (on no node).
    for (unsigned int d = 0; d < dim; ++d)
      std::fill(R + d * N + n_bits, R + (d + 1) * N, 0.);
    // Flag the CSR copies of the newly broken bonds (rare).
    for (const auto &[h, L] : sweep_broken)
      {
        const std::int32_t lower = sweep_node[L], upper = sweep_node[L + sweep_offset[h]];
        if (lower < std::int32_t(n_owned))
          broken_flag[find_sweep_bond(lower, h, false, upper)] = 1;
        if (upper < std::int32_t(n_owned))
          broken_flag[find_sweep_bond(upper, h, true, lower)] = 1;
      }
#else
    (void)p;
    (void)finish;
    AssertThrow(false, ExcMessage("The lattice sweep is not compiled."));
#endif
  }

  template <int dim>
  void
  BondBasedOperator<dim>::compute_forces(const VectorField &u, VectorField &force)
  {
    const auto                    &nb = disc.neighborhood;
    const std::vector<Point<dim>> &x  = disc.position;
    const unsigned int             n_owned = disc.n_owned();

    if (!linearized && uses_lattice_sweep())
      {
        sweep_forces(u, force);
        return;
      }
    if (!linearized)
      {
        // Deformed positions x - x_c + u of all local nodes, interleaved,
        // so that a bond loads one contiguous record. x_c is the lattice
        // centre (the same on every rank): |x - x_c| is at most half the
        // body, which bounds the round-off of y = p_j - p_i by
        // eps |x - x_c|.
        const std::size_t  n_local = x.size();
        constexpr unsigned int R   = node_stride<dim>;
        deformed.assign(n_local * R, 0.);
        const Point<dim> xc = deformation_origin();
        for (unsigned int d = 0; d < dim; ++d)
          {
            const double *ud = u[d].begin();
            for (std::size_t i = 0; i < n_local; ++i)
              deformed[R * i + d] = (x[i][d] - xc[d]) + ud[i];
          }
        if (half_list)
          half_list_forces(force);
        else
          full_list_forces(force);
        return;
      }

    // Linearized bond force (2.32): C(xi) eta = c omega beta V (xi.eta /
    // |xi|^3) xi, with xi and eta from positions so that the copy of the
    // bond in row j sees exactly -xi, -eta and hence the same stretch.
    std::array<const double *, dim> ud;
    for (unsigned int d = 0; d < dim; ++d)
      ud[d] = u[d].begin();
    for (unsigned int i = 0; i < n_owned; ++i)
      {
        const std::uint64_t begin = nb.row_start[i];
        const double       *coef  = bond_coefficient.data() + nb.table_start[i];
        double              f[dim] = {};
        for (std::uint64_t b = begin; b < nb.row_start[i + 1]; ++b)
          {
            if (broken_flag[b])
              continue;
            const std::int32_t j = nb.col[b];
            double             xi[dim], r2 = 0., xe = 0.;
            for (unsigned int d = 0; d < dim; ++d)
              {
                xi[d]            = x[j][d] - x[i][d];
                const double eta = ud[d][j] - ud[d][i];
                r2 += xi[d] * xi[d];
                xe += xi[d] * eta;
              }
            const double s = xe / r2;
            if (s > s0)
              {
                broken_flag[b] = 1;
                continue;
              }
            // coef = c omega beta V / |xi|, so the force is coef s xi.
            const double scale = coef[b - begin] * s;
            for (unsigned int d = 0; d < dim; ++d)
              f[d] += scale * xi[d];
          }
        for (unsigned int d = 0; d < dim; ++d)
          force[d].local_element(i) = f[d];
      }
  }

  template <int dim>
  void
  BondBasedOperator<dim>::strain_energy_density(const VectorField &u, Vector &W) const
  {
    const auto &nb = disc.neighborhood;
    const auto &x  = disc.position;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        const std::uint64_t begin = nb.row_start[i];
        const double       *coef  = bond_coefficient.data() + nb.table_start[i];
        double              w     = 0.;
        for (std::uint64_t b = begin; b < nb.row_start[i + 1]; ++b)
          {
            if (broken_flag[b])
              continue;
            const std::int32_t j = nb.col[b];
            double             r2 = 0., l2 = 0., xe = 0.;
            for (unsigned int d = 0; d < dim; ++d)
              {
                const double xi  = x[j][d] - x[i][d];
                const double eta = u[d].local_element(j) - u[d].local_element(i);
                r2 += xi * xi;
                l2 += (xi + eta) * (xi + eta);
                xe += xi * eta;
              }
            const double r = std::sqrt(r2);
            const double s = linearized ? xe / r2 : (std::sqrt(l2) - r) / r;
            w += coef[b - begin] * s * s * r2;
          }
        W.local_element(i) = 0.25 * w;
      }
  }

  template <int dim>
  double
  BondBasedOperator<dim>::total_strain_energy(const VectorField &u) const
  {
    Vector W;
    disc.initialize_vector(W);
    strain_energy_density(u, W);
    double e = 0.;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      e += W.local_element(i) * disc.volume[i];
    return Utilities::MPI::sum(e, disc.get_mpi_communicator());
  }

  template <int dim>
  void
  BondBasedOperator<dim>::damage(Vector &phi) const
  {
    BondDamage::compute_damage(disc, broken_flag, phi);
  }

  template <int dim>
  void
  BondBasedOperator<dim>::break_bonds(
    const std::function<bool(const Point<dim> &, const Point<dim> &)> &cuts)
  {
    const auto &nb = disc.neighborhood;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      for (std::uint64_t b = nb.row_start[i]; b < nb.row_start[i + 1]; ++b)
        {
          const std::int32_t j     = nb.col[b];
          const bool         first = disc.id[i] < disc.id[j];
          if (first ? cuts(disc.position[i], disc.position[j]) :
                      cuts(disc.position[j], disc.position[i]))
            broken_flag[b] = 1;
        }
    sweep_bits_valid = false;
  }

  template <int dim>
  void
  BondBasedOperator<dim>::add_precrack(const Point<dim> &a, const Point<dim> &b)
  {
    if constexpr (dim != 2)
      {
        (void)a;
        (void)b;
        throw ParameterError("Pre-crack", "a line segment in " + std::to_string(dim) + "D",
                             "line segments in 2D only (use break_bonds() otherwise)");
      }
    else
      {
        // Proper intersection by orientation signs: the segments cross iff
        // each one's end points lie strictly on opposite sides of the other.
        const auto orient = [](const Point<2> &p, const Point<2> &q, const Point<2> &r) {
          return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]);
        };
        break_bonds([&](const Point<2> &p, const Point<2> &q) {
          return orient(a, b, p) * orient(a, b, q) < 0. && orient(p, q, a) * orient(p, q, b) < 0.;
        });
      }
  }

  template <int dim>
  void
  BondBasedOperator<dim>::add_precrack(const std::vector<Point<dim>> &polygon)
  {
    if constexpr (dim == 2)
      {
        check_parameter(polygon.size() == 2, "Pre-crack", polygon.size(),
                        "2 vertices (a segment) in 2D");
        add_precrack(polygon[0], polygon[1]);
      }
    else if constexpr (dim == 3)
      {
        check_parameter(polygon.size() >= 3, "Pre-crack", polygon.size(),
                        "at least 3 vertices of a planar polygon in 3D");
        // Newell's normal (robust for non-convex polygons) and the size.
        Tensor<1, 3> n;
        double       size = 0.;
        for (std::size_t k = 0; k < polygon.size(); ++k)
          {
            const Point<3> &p = polygon[k], &q = polygon[(k + 1) % polygon.size()];
            n[0] += (p[1] - q[1]) * (p[2] + q[2]);
            n[1] += (p[2] - q[2]) * (p[0] + q[0]);
            n[2] += (p[0] - q[0]) * (p[1] + q[1]);
            size = std::max(size, p.distance(polygon[0]));
          }
        check_parameter(n.norm() > 1e-12 * size * size, "Pre-crack", "a degenerate polygon",
                        "a polygon of non-zero area");
        n /= n.norm();
        const Point<3> &o = polygon[0];
        for (const auto &p : polygon)
          check_parameter(std::abs(n * (p - o)) <= 1e-10 * size, "Pre-crack",
                          "a non-planar polygon", "the vertices of a planar polygon");
        // In-plane coordinates: drop the dominant normal component.
        unsigned int drop = 0;
        for (unsigned int d = 1; d < 3; ++d)
          if (std::abs(n[d]) > std::abs(n[drop]))
            drop = d;
        const unsigned int a0 = (drop + 1) % 3, a1 = (drop + 2) % 3;
        const auto inside = [&](const Point<3> &x) {
          bool in = false;
          for (std::size_t k = 0, l = polygon.size() - 1; k < polygon.size(); l = k++)
            {
              const Point<3> &p = polygon[k], &q = polygon[l];
              if ((p[a1] > x[a1]) != (q[a1] > x[a1]) &&
                  x[a0] < (q[a0] - p[a0]) * (x[a1] - p[a1]) / (q[a1] - p[a1]) + p[a0])
                in = !in;
            }
          return in;
        };
        break_bonds([&](const Point<3> &p, const Point<3> &q) {
          const double sp = n * (p - o), sq = n * (q - o);
          if (!(sp * sq < 0.))
            return false;
          return inside(p + sp / (sp - sq) * (q - p));
        });
      }
    else
      throw ParameterError("Pre-crack", "a polygon in 1D", "segments in 2D, polygons in 3D");
  }

  template <int dim>
  void
  BondBasedOperator<dim>::set_broken_flags(const std::vector<std::uint8_t> &flags)
  {
    AssertThrow(flags.size() == broken_flag.size(),
                ExcMessage("One broken flag per bond of the owned rows is needed."));
    broken_flag      = flags;
    sweep_bits_valid = false;
  }

  template <int dim>
  std::uint64_t
  BondBasedOperator<dim>::n_broken_bonds() const
  {
    return BondDamage::count_broken(broken_flag, disc.get_mpi_communicator());
  }

  template <int dim>
  double
  BondBasedOperator<dim>::critical_time_step(const double rho) const
  {
    double dt = std::numeric_limits<double>::max();
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (row_stiffness[i] > 0.)
        dt = std::min(dt, std::sqrt(2. * rho / row_stiffness[i]));
    return Utilities::MPI::min(dt, disc.get_mpi_communicator());
  }

  template class BondBasedOperator<1>;
  template class BondBasedOperator<2>;
  template class BondBasedOperator<3>;
} // namespace PeriDEAL
