//! CSV tables from typed rows: the header and every row come from one `Serialize` type (the
//! `csv` crate names the columns after its fields), floats in their shortest exact form, and
//! readers deserialize by column name. Every table the tool writes goes through here.

use std::path::Path;

use serde::Serialize;

use super::atomic::write_atomic;

/// CSV text of `rows`, with the header line of `T` first when `header` is set.
pub fn csv_text<T: Serialize>(rows: &[T], header: bool) -> anyhow::Result<String> {
    let mut w = csv::WriterBuilder::new().has_headers(header).from_writer(Vec::new());
    for r in rows {
        w.serialize(r)?;
    }
    Ok(String::from_utf8(w.into_inner().map_err(|e| anyhow::anyhow!("writing CSV: {e}"))?)?)
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
}
