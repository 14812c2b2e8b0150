//! The buffers (glTF 2.0 §3.6.1): the GLB BIN chunk, base64 `data:` URIs and external files by
//! relative path (§2.8), each loaded once, when first needed, and checked against `byteLength`.

use std::borrow::Cow;
use std::path::Path;

use ::gltf::json;
use base64::Engine as _;
use base64::alphabet;
use base64::engine::{DecodePaddingMode, GeneralPurpose, GeneralPurposeConfig};

use super::item;
use crate::InputError;

/// The buffers, each loaded when first needed and checked against its `byteLength`.
pub(super) struct Buffers<'a, 'r> {
    root: &'a json::Root,
    path: &'a Path,
    bin: Option<&'a [u8]>,
    resolve: &'r mut dyn FnMut(&str) -> Result<Vec<u8>, InputError>,
    /// The first `byteLength` bytes of each buffer loaded so far.
    data: Vec<Option<Cow<'a, [u8]>>>,
}

impl<'a, 'r> Buffers<'a, 'r> {
    /// The buffers of `root`, none loaded yet; `bin` is a GLB's BIN chunk, `resolve` reads
    /// external ones ([`super::parse_gltf`]).
    pub(super) fn new(
        root: &'a json::Root,
        path: &'a Path,
        bin: Option<&'a [u8]>,
        resolve: &'r mut dyn FnMut(&str) -> Result<Vec<u8>, InputError>,
    ) -> Self {
        Buffers {
            root,
            path,
            bin,
            resolve,
            data: vec![None; root.buffers.len()],
        }
    }

    /// Loads buffer `b` unless it is loaded.
    pub(super) fn load(&mut self, b: usize) -> Result<(), InputError> {
        if self.data.get(b).is_some_and(Option::is_some) {
            return Ok(());
        }
        let buffer = item(&self.root.buffers, b, self.path, || format!("buffers[{b}]"))?;
        let length = buffer.byte_length.0;
        let data = self.fetch(b, buffer.uri.as_deref())?;
        if (data.len() as u64) < length {
            let (field, value) = match &buffer.uri {
                Some(uri) => (format!("buffers[{b}].uri"), uri.clone()),
                None => (format!("buffers[{b}].byteLength"), length.to_string()),
            };
            return Err(InputError::new(
                self.path,
                field,
                value,
                format!(
                    "the buffer has {} bytes, fewer than its byteLength {length}",
                    data.len()
                ),
            ));
        }
        // glTF 2.0 §3.6.1.2: a BIN chunk may be up to 3 bytes longer (padding); only the
        // first byteLength bytes are the buffer.
        let data = match data {
            Cow::Borrowed(bytes) => Cow::Borrowed(&bytes[..length as usize]),
            Cow::Owned(mut bytes) => {
                bytes.truncate(length as usize);
                Cow::Owned(bytes)
            }
        };
        if let Some(slot) = self.data.get_mut(b) {
            *slot = Some(data);
        }
        Ok(())
    }

    /// The bytes of buffer `b`: the GLB BIN chunk, a `data:` URI, or an external file.
    fn fetch(&mut self, b: usize, uri: Option<&str>) -> Result<Cow<'a, [u8]>, InputError> {
        let field = || format!("buffers[{b}].uri");
        let err = |value: &str, reason: String| InputError::new(self.path, field(), value, reason);
        match uri {
            None if b == 0 => self.bin.map(Cow::Borrowed).ok_or_else(|| {
                err(
                    "(absent)",
                    "a buffer without uri is the GLB BIN chunk, and the file has none".into(),
                )
            }),
            None => Err(err(
                "(absent)",
                "only buffer 0 may omit its uri (it is then the GLB BIN chunk)".into(),
            )),
            Some(uri) if is_data_uri(uri) => data_uri(uri).map(Cow::Owned).map_err(|r| err(uri, r)),
            Some(uri) => {
                let relative = relative_path(uri).map_err(|r| err(uri, r))?;
                let bytes = (self.resolve)(&relative).map_err(|e| err(uri, e.reason))?;
                Ok(Cow::Owned(bytes))
            }
        }
    }

    /// The loaded bytes of buffer `b` (empty if it is not loaded).
    pub(super) fn bytes(&self, b: usize) -> &[u8] {
        self.data.get(b).and_then(Option::as_deref).unwrap_or(&[])
    }
}

/// Whether `uri` has the scheme `data:` (schemes are case-insensitive).
fn is_data_uri(uri: &str) -> bool {
    uri.get(..5)
        .is_some_and(|s| s.eq_ignore_ascii_case("data:"))
}

/// Base64 as `data:` URIs carry it, padded or not.
const DATA_BASE64: GeneralPurpose = GeneralPurpose::new(
    &alphabet::STANDARD,
    GeneralPurposeConfig::new().with_decode_padding_mode(DecodePaddingMode::Indifferent),
);

/// The bytes of a base64 `data:` URI (`data:[<media type>];base64,<data>`, glTF 2.0 §2.8).
fn data_uri(uri: &str) -> Result<Vec<u8>, String> {
    let (header, payload) = uri
        .split_once(',')
        .ok_or("a data: URI has a `,` before its data")?;
    if !header.to_ascii_lowercase().ends_with(";base64") {
        return Err("only base64 data: URIs are read (`;base64,` before the data)".into());
    }
    DATA_BASE64
        .decode(payload)
        .map_err(|e| format!("not valid base64: {e}"))
}

/// The relative path a buffer's `uri` names, percent-decoded, or why it is refused (§2.8).
fn relative_path(uri: &str) -> Result<String, String> {
    let scheme = uri.split_once(':').map(|(s, _)| s).filter(|s| {
        s.starts_with(|c: char| c.is_ascii_alphabetic())
            && s.chars()
                .all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
    });
    if let Some(scheme) = scheme {
        return Err(format!(
            "the scheme `{scheme}:` is not read: a buffer is a relative path or a base64 data: URI"
        ));
    }
    if uri.is_empty() || uri.contains(['?', '#']) {
        return Err("a buffer's uri is a non-empty relative path without query or fragment".into());
    }
    let decoded = percent_decode(uri).ok_or("malformed percent-encoding or not UTF-8")?;
    if decoded.starts_with(['/', '\\']) || Path::new(&decoded).is_absolute() {
        return Err("an absolute path: buffers are relative to the glTF file".into());
    }
    Ok(decoded)
}

/// `text` with each `%XX` replaced by its byte, if that is valid UTF-8.
fn percent_decode(text: &str) -> Option<String> {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = bytes.get(i + 1..i + 3)?;
            let digit = |b: u8| (b as char).to_digit(16);
            out.push((digit(hex[0])? * 16 + digit(hex[1])?) as u8);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}
