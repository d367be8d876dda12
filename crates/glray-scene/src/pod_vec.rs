//! A `Vec` of plain numbers (positions, triangles, texels) in the byte encoding as its bytes:
//! one copy, not a value at a time (`#[serde(with = "crate::pod_vec")]`). The bytes are in the
//! sender's byte order; `encode`'s header names it.

use std::marker::PhantomData;

use bytemuck::Pod;
use serde::de::{SeqAccess, Visitor};

pub fn serialize<T: Pod, S: serde::Serializer>(v: &[T], s: S) -> Result<S::Ok, S::Error> {
    s.serialize_bytes(bytemuck::cast_slice(v))
}

pub fn deserialize<'de, T: Pod, D: serde::Deserializer<'de>>(d: D) -> Result<Vec<T>, D::Error> {
    struct Bytes<T>(PhantomData<T>);
    impl<'de, T: Pod> Visitor<'de> for Bytes<T> {
        type Value = Vec<T>;

        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            write!(f, "the bytes of an array of {}-byte values", std::mem::size_of::<T>())
        }

        fn visit_bytes<E: serde::de::Error>(self, b: &[u8]) -> Result<Vec<T>, E> {
            if b.len() % std::mem::size_of::<T>() != 0 {
                return Err(E::custom(format!("{} bytes is not a whole number of values", b.len())));
            }
            Ok(bytemuck::pod_collect_to_vec(b))
        }

        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Vec<T>, A::Error> {
            let mut bytes = Vec::new();
            while let Some(b) = seq.next_element::<u8>()? {
                bytes.push(b);
            }
            self.visit_bytes(&bytes)
        }
    }
    d.deserialize_bytes(Bytes(PhantomData))
}
