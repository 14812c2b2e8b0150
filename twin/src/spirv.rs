//! The struct layouts `glslc` chose, read back from SPIR-V: `engine/build.rs` compiles a probe
//! shader that declares every contract struct (and one per push-constant block) without `-O`,
//! so debug names stay, and compares these layouts with the Rust ones.

use std::collections::HashMap;

const OP_NAME: u32 = 5;
const OP_TYPE_RUNTIME_ARRAY: u32 = 29;
const OP_DECORATE: u32 = 71;
const OP_MEMBER_DECORATE: u32 = 72;
const DECORATION_ARRAY_STRIDE: u32 = 6;
const DECORATION_OFFSET: u32 = 35;
const MAGIC: u32 = 0x0723_0203;

/// A named struct type of a SPIR-V module as laid out there.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Layout {
    /// Byte offset of each member, in member order.
    pub offsets: Vec<u32>,
    /// The stride of a runtime array (`T name[]`) of the struct, if the module has one: its
    /// size in an array.
    pub array_stride: Option<u32>,
}

/// The layout of every named struct type with member offsets, by name; `Err` for bytes that
/// are not a well-formed SPIR-V module.
pub fn layouts(bytes: &[u8]) -> Result<HashMap<String, Layout>, String> {
    if bytes.len() % 4 != 0 || bytes.len() < 20 {
        return Err(format!("{} bytes are not a SPIR-V module", bytes.len()));
    }
    let words: Vec<u32> = bytes
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    if words[0] != MAGIC {
        return Err(format!("magic number {:#x}, not SPIR-V", words[0]));
    }
    let mut names = HashMap::new();
    let mut members: HashMap<u32, Vec<(u32, u32)>> = HashMap::new();
    let mut array_of = HashMap::new();
    let mut strides = HashMap::new();
    let mut i = 5;
    while i < words.len() {
        let (op, count) = (words[i] & 0xffff, (words[i] >> 16) as usize);
        if count == 0 || i + count > words.len() {
            return Err(format!("truncated instruction at word {i}"));
        }
        let operands = &words[i + 1..i + count];
        match (op, operands) {
            (OP_NAME, [id, text @ ..]) => {
                let bytes: Vec<u8> = text.iter().flat_map(|w| w.to_le_bytes()).collect();
                let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
                names.insert(*id, String::from_utf8_lossy(&bytes[..end]).into_owned());
            }
            (OP_TYPE_RUNTIME_ARRAY, [array, element]) => {
                array_of.insert(*array, *element);
            }
            (OP_DECORATE, [target, DECORATION_ARRAY_STRIDE, stride]) => {
                strides.insert(*target, *stride);
            }
            (OP_MEMBER_DECORATE, [ty, member, DECORATION_OFFSET, offset]) => {
                members.entry(*ty).or_default().push((*member, *offset));
            }
            _ => {}
        }
        i += count;
    }
    let mut out: HashMap<String, Layout> = HashMap::new();
    for (id, mut offsets) in members {
        let Some(name) = names.get(&id) else { continue };
        offsets.sort_unstable();
        let array_stride = array_of
            .iter()
            .find(|&(array, element)| *element == id && strides.contains_key(array))
            .map(|(array, _)| strides[array]);
        out.insert(
            name.clone(),
            Layout {
                offsets: offsets.into_iter().map(|(_, o)| o).collect(),
                array_stride,
            },
        );
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn instruction(op: u32, operands: &[u32]) -> Vec<u32> {
        let mut words = vec![op | ((operands.len() as u32 + 1) << 16)];
        words.extend_from_slice(operands);
        words
    }

    #[test]
    fn reads_named_member_offsets_and_array_strides() {
        let mut words = vec![MAGIC, 0x0001_0500, 0, 10, 0];
        let name = u32::from_le_bytes(*b"Ab\0\0");
        words.extend(instruction(OP_NAME, &[7, name]));
        words.extend(instruction(
            OP_MEMBER_DECORATE,
            &[7, 1, DECORATION_OFFSET, 12],
        ));
        words.extend(instruction(
            OP_MEMBER_DECORATE,
            &[7, 0, DECORATION_OFFSET, 0],
        ));
        words.extend(instruction(
            OP_MEMBER_DECORATE,
            &[8, 0, DECORATION_OFFSET, 4],
        ));
        words.extend(instruction(OP_DECORATE, &[9, DECORATION_ARRAY_STRIDE, 16]));
        words.extend(instruction(OP_TYPE_RUNTIME_ARRAY, &[9, 7]));
        let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
        let found = layouts(&bytes).unwrap();
        assert_eq!(found.len(), 1, "unnamed type 8 is left out");
        assert_eq!(
            found["Ab"],
            Layout {
                offsets: vec![0, 12],
                array_stride: Some(16)
            }
        );
        assert!(layouts(&bytes[4..]).is_err());
        assert!(layouts(&bytes[..bytes.len() - 2]).is_err());
        assert!(layouts(&bytes[..bytes.len() - 4]).is_err());
    }
}
