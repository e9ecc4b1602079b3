//! CSV tables from typed rows: the header and every row come from one `Serialize` type (the
//! columns are named after its fields; a `#[serde(flatten)]` field, such as the design's
//! eight columns `model::design::DesignRow`, puts its columns in its place), floats in their
//! shortest exact form, and readers deserialize by column name with `csv`. Every table the
//! tool writes goes through here.

use std::fmt;
use std::path::Path;

use serde::ser::{self, Impossible, Serialize};

use super::atomic::write_atomic;

/// CSV text of `rows`, with the header line of `T` first when `header` is set.
pub fn csv_text<T: Serialize>(rows: &[T], header: bool) -> anyhow::Result<String> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for (i, r) in rows.iter().enumerate() {
        let cells = Cells::of(r)?;
        if header && i == 0 {
            w.write_record(&cells.names)?;
        }
        w.write_record(&cells.texts)?;
    }
    Ok(String::from_utf8(w.into_inner().map_err(|e| anyhow::anyhow!("writing CSV: {e}"))?)?)
}

/// One row as its column names and cell texts. The `csv` crate's own serializer refuses the
/// map serde makes of a struct with a flattened field, so rows are taken apart here and
/// written with `write_record`; each cell is written as `csv` writes it (floats in ryu's
/// shortest form, `None` empty, an enum by its variant's name), so a table reads the same
/// with either.
#[derive(Default)]
struct Cells {
    names: Vec<String>,
    texts: Vec<String>,
    /// a map entry's key, until its value comes
    key: Option<String>,
}

impl Cells {
    fn of<T: Serialize + ?Sized>(row: &T) -> Result<Self, TableError> {
        let mut cells = Cells::default();
        row.serialize(&mut cells)?;
        Ok(cells)
    }
}

#[derive(Debug)]
struct TableError(String);

impl fmt::Display for TableError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "writing a table row: {}", self.0)
    }
}

impl std::error::Error for TableError {}

impl ser::Error for TableError {
    fn custom<T: fmt::Display>(msg: T) -> Self {
        TableError(msg.to_string())
    }
}

fn not_a_row<T>(what: &str) -> Result<T, TableError> {
    Err(TableError(format!("a table row must be a struct, got {what}")))
}

impl ser::Serializer for &mut Cells {
    type Ok = ();
    type Error = TableError;
    type SerializeSeq = Impossible<(), TableError>;
    type SerializeTuple = Impossible<(), TableError>;
    type SerializeTupleStruct = Impossible<(), TableError>;
    type SerializeTupleVariant = Impossible<(), TableError>;
    type SerializeMap = Self;
    type SerializeStruct = Self;
    type SerializeStructVariant = Impossible<(), TableError>;

    fn serialize_struct(self, _: &'static str, _: usize) -> Result<Self, TableError> {
        Ok(self)
    }
    /// What serde makes of a struct with a `#[serde(flatten)]` field.
    fn serialize_map(self, _: Option<usize>) -> Result<Self, TableError> {
        Ok(self)
    }
    fn serialize_bool(self, _: bool) -> Result<(), TableError> {
        not_a_row("a bool")
    }
    fn serialize_i8(self, _: i8) -> Result<(), TableError> {
        not_a_row("a number")
    }
    fn serialize_i16(self, _: i16) -> Result<(), TableError> {
        not_a_row("a number")
    }
    fn serialize_i32(self, _: i32) -> Result<(), TableError> {
        not_a_row("a number")
    }
    fn serialize_i64(self, _: i64) -> Result<(), TableError> {
        not_a_row("a number")
    }
    fn serialize_u8(self, _: u8) -> Result<(), TableError> {
        not_a_row("a number")
    }
    fn serialize_u16(self, _: u16) -> Result<(), TableError> {
        not_a_row("a number")
    }
    fn serialize_u32(self, _: u32) -> Result<(), TableError> {
        not_a_row("a number")
    }
    fn serialize_u64(self, _: u64) -> Result<(), TableError> {
        not_a_row("a number")
    }
    fn serialize_f32(self, _: f32) -> Result<(), TableError> {
        not_a_row("a number")
    }
    fn serialize_f64(self, _: f64) -> Result<(), TableError> {
        not_a_row("a number")
    }
    fn serialize_char(self, _: char) -> Result<(), TableError> {
        not_a_row("a char")
    }
    fn serialize_str(self, _: &str) -> Result<(), TableError> {
        not_a_row("a string")
    }
    fn serialize_bytes(self, _: &[u8]) -> Result<(), TableError> {
        not_a_row("bytes")
    }
    fn serialize_none(self) -> Result<(), TableError> {
        not_a_row("an option")
    }
    fn serialize_some<T: Serialize + ?Sized>(self, _: &T) -> Result<(), TableError> {
        not_a_row("an option")
    }
    fn serialize_unit(self) -> Result<(), TableError> {
        not_a_row("()")
    }
    fn serialize_unit_struct(self, _: &'static str) -> Result<(), TableError> {
        not_a_row("a unit struct")
    }
    fn serialize_unit_variant(self, _: &'static str, _: u32, _: &'static str) -> Result<(), TableError> {
        not_a_row("an enum")
    }
    fn serialize_newtype_struct<T: Serialize + ?Sized>(self, _: &'static str, v: &T) -> Result<(), TableError> {
        v.serialize(self)
    }
    fn serialize_newtype_variant<T: Serialize + ?Sized>(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: &T,
    ) -> Result<(), TableError> {
        not_a_row("an enum")
    }
    fn serialize_seq(self, _: Option<usize>) -> Result<Self::SerializeSeq, TableError> {
        not_a_row("a sequence")
    }
    fn serialize_tuple(self, _: usize) -> Result<Self::SerializeTuple, TableError> {
        not_a_row("a tuple")
    }
    fn serialize_tuple_struct(self, _: &'static str, _: usize) -> Result<Self::SerializeTupleStruct, TableError> {
        not_a_row("a tuple struct")
    }
    fn serialize_tuple_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeTupleVariant, TableError> {
        not_a_row("an enum")
    }
    fn serialize_struct_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeStructVariant, TableError> {
        not_a_row("an enum")
    }
}

impl ser::SerializeStruct for &mut Cells {
    type Ok = ();
    type Error = TableError;
    fn serialize_field<T: Serialize + ?Sized>(&mut self, key: &'static str, value: &T) -> Result<(), TableError> {
        self.names.push(key.to_string());
        self.texts.push(value.serialize(CellText).map_err(|e| TableError(format!("column `{key}`: {}", e.0)))?);
        Ok(())
    }
    fn end(self) -> Result<(), TableError> {
        Ok(())
    }
}

impl ser::SerializeMap for &mut Cells {
    type Ok = ();
    type Error = TableError;
    fn serialize_key<T: Serialize + ?Sized>(&mut self, key: &T) -> Result<(), TableError> {
        self.key = Some(key.serialize(CellText)?);
        Ok(())
    }
    fn serialize_value<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<(), TableError> {
        let key = self.key.take().ok_or_else(|| TableError("a value without its column".into()))?;
        let text = value.serialize(CellText).map_err(|e| TableError(format!("column `{key}`: {}", e.0)))?;
        self.names.push(key);
        self.texts.push(text);
        Ok(())
    }
    fn end(self) -> Result<(), TableError> {
        Ok(())
    }
}

/// One cell's text, as the `csv` crate writes the value.
struct CellText;

fn not_a_cell<T>(what: &str) -> Result<T, TableError> {
    Err(TableError(format!("a cell must hold one value, got {what}")))
}

/// ryu's shortest round-trip form, as `csv` writes floats (NaN, inf and -inf included).
fn float_text<F: ryu::Float>(v: F) -> String {
    ryu::Buffer::new().format(v).to_string()
}

impl ser::Serializer for CellText {
    type Ok = String;
    type Error = TableError;
    type SerializeSeq = Impossible<String, TableError>;
    type SerializeTuple = Impossible<String, TableError>;
    type SerializeTupleStruct = Impossible<String, TableError>;
    type SerializeTupleVariant = Impossible<String, TableError>;
    type SerializeMap = Impossible<String, TableError>;
    type SerializeStruct = Impossible<String, TableError>;
    type SerializeStructVariant = Impossible<String, TableError>;

    fn serialize_bool(self, v: bool) -> Result<String, TableError> {
        Ok(v.to_string())
    }
    fn serialize_i8(self, v: i8) -> Result<String, TableError> {
        Ok(v.to_string())
    }
    fn serialize_i16(self, v: i16) -> Result<String, TableError> {
        Ok(v.to_string())
    }
    fn serialize_i32(self, v: i32) -> Result<String, TableError> {
        Ok(v.to_string())
    }
    fn serialize_i64(self, v: i64) -> Result<String, TableError> {
        Ok(v.to_string())
    }
    fn serialize_i128(self, v: i128) -> Result<String, TableError> {
        Ok(v.to_string())
    }
    fn serialize_u8(self, v: u8) -> Result<String, TableError> {
        Ok(v.to_string())
    }
    fn serialize_u16(self, v: u16) -> Result<String, TableError> {
        Ok(v.to_string())
    }
    fn serialize_u32(self, v: u32) -> Result<String, TableError> {
        Ok(v.to_string())
    }
    fn serialize_u64(self, v: u64) -> Result<String, TableError> {
        Ok(v.to_string())
    }
    fn serialize_u128(self, v: u128) -> Result<String, TableError> {
        Ok(v.to_string())
    }
    fn serialize_f32(self, v: f32) -> Result<String, TableError> {
        Ok(float_text(v))
    }
    fn serialize_f64(self, v: f64) -> Result<String, TableError> {
        Ok(float_text(v))
    }
    fn serialize_char(self, v: char) -> Result<String, TableError> {
        Ok(v.to_string())
    }
    fn serialize_str(self, v: &str) -> Result<String, TableError> {
        Ok(v.to_string())
    }
    fn serialize_bytes(self, _: &[u8]) -> Result<String, TableError> {
        not_a_cell("bytes")
    }
    fn serialize_none(self) -> Result<String, TableError> {
        Ok(String::new())
    }
    fn serialize_some<T: Serialize + ?Sized>(self, v: &T) -> Result<String, TableError> {
        v.serialize(self)
    }
    fn serialize_unit(self) -> Result<String, TableError> {
        Ok(String::new())
    }
    fn serialize_unit_struct(self, name: &'static str) -> Result<String, TableError> {
        Ok(name.to_string())
    }
    fn serialize_unit_variant(self, _: &'static str, _: u32, variant: &'static str) -> Result<String, TableError> {
        Ok(variant.to_string())
    }
    fn serialize_newtype_struct<T: Serialize + ?Sized>(self, _: &'static str, v: &T) -> Result<String, TableError> {
        v.serialize(self)
    }
    fn serialize_newtype_variant<T: Serialize + ?Sized>(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        v: &T,
    ) -> Result<String, TableError> {
        v.serialize(self)
    }
    fn serialize_seq(self, _: Option<usize>) -> Result<Self::SerializeSeq, TableError> {
        not_a_cell("a sequence")
    }
    fn serialize_tuple(self, _: usize) -> Result<Self::SerializeTuple, TableError> {
        not_a_cell("a tuple")
    }
    fn serialize_tuple_struct(self, _: &'static str, _: usize) -> Result<Self::SerializeTupleStruct, TableError> {
        not_a_cell("a tuple struct")
    }
    fn serialize_tuple_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeTupleVariant, TableError> {
        not_a_cell("an enum with fields")
    }
    fn serialize_map(self, _: Option<usize>) -> Result<Self::SerializeMap, TableError> {
        not_a_cell("a map")
    }
    fn serialize_struct(self, _: &'static str, _: usize) -> Result<Self::SerializeStruct, TableError> {
        not_a_cell("a struct (flatten it into the row)")
    }
    fn serialize_struct_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeStructVariant, TableError> {
        not_a_cell("an enum with fields")
    }
}

/// Serializes an optional group of columns that a row flattens into its place
/// (`#[serde(flatten, serialize_with = "optional_columns")]` on an `Option<T>`): the group's
/// columns, each cell empty where there is no group (a study run whose front holds no design).
/// serde leaves a flattened `None` out of the row, which would shift the columns after it;
/// the names come from `T::default()`. Read back, the flattened `Option<T>` is `None` when
/// the cells are empty.
pub fn optional_columns<T: Serialize + Default, S: ser::Serializer>(
    group: &Option<T>,
    s: S,
) -> Result<S::Ok, S::Error> {
    use ser::{Error as _, SerializeMap as _};
    match group {
        Some(g) => g.serialize(s),
        None => {
            let names = Cells::of(&T::default()).map_err(|e| S::Error::custom(e.0))?.names;
            let mut columns = s.serialize_map(Some(names.len()))?;
            for name in &names {
                columns.serialize_entry(name, &None::<()>)?;
            }
            columns.end()
        }
    }
}

/// The header line of `T`'s table (from a default row, whose values are dropped).
pub fn csv_header<T: Serialize + Default>() -> anyhow::Result<String> {
    let text = csv_text(&[T::default()], true)?;
    Ok(text.lines().next().unwrap_or_default().to_string() + "\n")
}

/// The whole table of `rows`: the header (even with no rows), then the rows.
pub fn table_text<T: Serialize + Default>(rows: &[T]) -> anyhow::Result<String> {
    if rows.is_empty() {
        csv_header::<T>()
    } else {
        csv_text(rows, true)
    }
}

/// Write the table of `rows` to `path` atomically.
pub fn write_table<T: Serialize + Default>(path: &Path, rows: &[T]) -> anyhow::Result<()> {
    write_atomic(path, table_text(rows)?.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Serialize;

    #[derive(Default, Serialize, serde::Deserialize, Debug, PartialEq)]
    struct Row {
        tooth: u32,
        share_percent: Option<f64>,
        lost: bool,
    }

    #[test]
    fn header_and_rows_come_from_the_type_and_read_back_exactly() {
        let rows = [
            Row { tooth: 1, share_percent: Some(0.1 + 0.2), lost: false },
            Row { tooth: 2, share_percent: None, lost: true },
        ];
        let text = csv_text(&rows, true).unwrap();
        assert_eq!(text, "tooth,share_percent,lost\n1,0.30000000000000004,false\n2,,true\n");
        assert_eq!(csv_header::<Row>().unwrap(), "tooth,share_percent,lost\n");
        let back: Vec<Row> = csv::Reader::from_reader(text.as_bytes()).deserialize().collect::<Result<_, _>>().unwrap();
        assert_eq!(back, rows);
        let d = tempfile::tempdir().unwrap();
        write_table::<Row>(&d.path().join("empty.csv"), &[]).unwrap();
        assert_eq!(std::fs::read_to_string(d.path().join("empty.csv")).unwrap(), "tooth,share_percent,lost\n");
    }

    #[derive(Default, Serialize, serde::Deserialize, Debug, PartialEq)]
    enum Limit {
        #[default]
        Frequency,
    }

    #[derive(Default, Serialize, serde::Deserialize, Debug, PartialEq)]
    struct Scalars {
        name: String,
        quoted: String,
        small: f64,
        large: f64,
        not_a_number: f64,
        infinite: f64,
        single: f32,
        negative: i64,
        limit: Limit,
        maybe: Option<u32>,
    }

    /// The cells are the `csv` crate's own text for every kind of value the rows hold, so
    /// files keep their bytes whichever writer made them.
    #[test]
    fn cells_are_written_as_the_csv_crate_writes_them() {
        let rows = [
            Scalars {
                name: "plain".into(),
                quoted: "a, \"b\"\nc".into(),
                small: 1e-7,
                large: 1e16,
                not_a_number: f64::NAN,
                infinite: f64::NEG_INFINITY,
                single: 0.1,
                negative: -3,
                limit: Limit::Frequency,
                maybe: Some(4),
            },
            Scalars { large: 0.1 + 0.2, infinite: f64::INFINITY, ..Default::default() },
        ];
        let mut w = csv::Writer::from_writer(Vec::new());
        for r in &rows {
            w.serialize(r).unwrap();
        }
        let theirs = String::from_utf8(w.into_inner().unwrap()).unwrap();
        assert_eq!(csv_text(&rows, true).unwrap(), theirs);
    }

    #[derive(Default, Serialize, serde::Deserialize, Debug, PartialEq)]
    struct Inner {
        x_mm: f64,
        y_mm: f64,
    }

    #[derive(Default, Serialize, serde::Deserialize, Debug, PartialEq)]
    struct Flattened {
        run: u32,
        #[serde(flatten)]
        inner: Inner,
        figure: Option<f64>,
    }

    #[test]
    fn a_flattened_fields_columns_stand_in_its_place_and_read_back() {
        let rows = [
            Flattened { run: 1, inner: Inner { x_mm: 47.346, y_mm: 2.0 }, figure: Some(0.5) },
            Flattened { run: 2, inner: Inner { x_mm: 1e-9, y_mm: -0.0 }, figure: None },
        ];
        let text = csv_text(&rows, true).unwrap();
        assert_eq!(text, "run,x_mm,y_mm,figure\n1,47.346,2.0,0.5\n2,1e-9,-0.0,\n");
        assert_eq!(csv_header::<Flattened>().unwrap(), "run,x_mm,y_mm,figure\n");
        let back: Vec<Flattened> =
            csv::Reader::from_reader(text.as_bytes()).deserialize().collect::<Result<_, _>>().unwrap();
        assert_eq!(back, rows);
    }

    #[test]
    fn a_row_that_is_not_a_struct_is_refused() {
        assert!(csv_text(&[1.0], true).unwrap_err().to_string().contains("must be a struct"));
        #[derive(Serialize)]
        struct Nested {
            inner: Inner,
        }
        let e = csv_text(&[Nested { inner: Inner::default() }], true).unwrap_err().to_string();
        assert!(e.contains("column `inner`") && e.contains("flatten"), "{e}");
    }
}
