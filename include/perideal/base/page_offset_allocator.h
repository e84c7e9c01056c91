#ifndef perideal_base_page_offset_allocator_h
#define perideal_base_page_offset_allocator_h

#include <cstddef>
#include <cstdlib>
#include <new>
#include <vector>

namespace PeriDEAL
{
  /**
   * A std::allocator replacement whose arrays start at a chosen byte offset
   * (a multiple of 64) within a 4 kB page.
   *
   * Why: glibc serves large arrays by mmap, so every one of them starts 16
   * bytes into a page. Streams that run in step over several such arrays
   * (the lattice sweep loads the deformed positions at L + o while it
   * updates the reactions at L + o; the Verlet kicks read and write six box
   * arrays at L) then have equal address bits 0-11, and a load that follows
   * a store to another array at the same page offset waits for it (4K
   * aliasing). Giving each array its own page offset, and 64-byte
   * alignment (a vector of eight doubles at a multiple of 8 then stays in
   * one cache line), removes that; the values are unchanged.
   */
  template <typename T>
  class PageOffsetAllocator
  {
  public:
    using value_type = T;

    /** Arrays start at @p page_offset (rounded down to a multiple of 64) mod 4096. */
    explicit PageOffsetAllocator(const std::size_t page_offset = 0) noexcept
      : offset(page_offset % page / 64 * 64)
    {}

    template <typename U>
    PageOffsetAllocator(const PageOffsetAllocator<U> &other) noexcept
      : offset(other.offset)
    {}

    T *
    allocate(const std::size_t n)
    {
      const std::size_t bytes = (n * sizeof(T) + offset + page - 1) / page * page;
      void             *base  = std::aligned_alloc(page, bytes);
      if (base == nullptr)
        throw std::bad_alloc();
      return reinterpret_cast<T *>(static_cast<char *>(base) + offset);
    }

    void
    deallocate(T *p, const std::size_t) noexcept
    {
      std::free(reinterpret_cast<char *>(p) - offset);
    }

    bool
    operator==(const PageOffsetAllocator &other) const noexcept
    {
      return offset == other.offset;
    }

    bool
    operator!=(const PageOffsetAllocator &other) const noexcept
    {
      return offset != other.offset;
    }

    /** Byte offset of the arrays within their first page. */
    std::size_t offset;

  private:
    static constexpr std::size_t page = 4096;
  };

  /** A vector of doubles at a given page offset (PageOffsetAllocator). */
  using PageOffsetVector = std::vector<double, PageOffsetAllocator<double>>;
} // namespace PeriDEAL

#endif
