//! The firmware image: its loadable segments (what a probe writes to flash), its
//! symbols (the RTT control block, the settings pages, the semihosting-free exit
//! markers), and the raw bytes the defmt decoder reads its table from.

use object::{Object, ObjectSegment, ObjectSymbol};
use std::collections::HashMap;
use std::path::Path;

pub struct Image {
    pub bytes: Vec<u8>,
    /// (physical address, bytes) of each loadable segment.
    pub segments: Vec<(u32, Vec<u8>)>,
    pub symbols: HashMap<String, u32>,
}

impl Image {
    pub fn read(path: &Path) -> Result<Image, String> {
        let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let file = object::File::parse(&*bytes).map_err(|e| format!("{}: {e}", path.display()))?;
        let mut segments = Vec::new();
        if let object::File::Elf32(elf) = &file {
            use object::read::elf::ProgramHeader;
            let endian = elf.endian();
            for ph in elf.elf_program_headers() {
                if ph.p_type(endian) != object::elf::PT_LOAD || ph.p_filesz(endian) == 0 {
                    continue;
                }
                let data = ph
                    .data(endian, &*bytes)
                    .map_err(|_| "bad program header".to_string())?;
                segments.push((ph.p_paddr(endian), data.to_vec()));
            }
        } else {
            for s in file.segments() {
                let data = s.data().map_err(|e| e.to_string())?;
                if !data.is_empty() {
                    segments.push((s.address() as u32, data.to_vec()));
                }
            }
        }
        let symbols = file
            .symbols()
            .filter_map(|s| Some((s.name().ok()?.to_string(), s.address() as u32)))
            .collect();
        Ok(Image {
            bytes,
            segments,
            symbols,
        })
    }

    pub fn symbol(&self, name: &str) -> Option<u32> {
        self.symbols.get(name).copied()
    }
}
