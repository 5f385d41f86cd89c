//! Reading back the CSV files this workspace writes (`ieee952_terms.csv`,
//! `ieee952_curves.csv`, `allan_curves.csv`, `sim`'s truth): `#` comment lines, a header,
//! comma-separated rows, each column found by its name. `check --against`, `sim compare`
//! and the charts' truth overlay all read them this one way.

/// A CSV file as this workspace writes it, split into its header and rows.
#[derive(Debug, Clone)]
pub struct OutputCsv<'a> {
    header: Vec<&'a str>,
    body: Vec<&'a str>,
}

impl<'a> OutputCsv<'a> {
    /// The header (the first line that is not a `#` comment) and the rows after it.
    pub fn parse(text: &'a str) -> OutputCsv<'a> {
        let mut lines = text.lines().filter(|l| !l.starts_with('#'));
        let header = lines.next().unwrap_or("").split(',').collect();
        OutputCsv {
            header,
            body: lines.collect(),
        }
    }

    /// The index of column `name`.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| *h == name)
    }

    /// The indices of `names`, or the first name the header lacks.
    pub fn columns<const K: usize>(&self, names: [&'a str; K]) -> Result<[usize; K], &'a str> {
        let mut out = [0; K];
        for (o, name) in out.iter_mut().zip(names) {
            *o = self.column(name).ok_or(name)?;
        }
        Ok(out)
    }

    /// The number of columns the header names.
    pub fn width(&self) -> usize {
        self.header.len()
    }

    /// Each row's fields.
    pub fn rows(&self) -> impl Iterator<Item = Vec<&'a str>> + '_ {
        self.body.iter().map(|l| l.split(',').collect())
    }
}

/// Field `i` of a row, "" past its end.
pub fn field<'a>(row: &[&'a str], i: usize) -> &'a str {
    row.get(i).copied().unwrap_or("")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn comments_are_skipped_and_columns_found_by_name() {
        let c = OutputCsv::parse("# a comment\nx,y,z\n1,2,3\n# another\n4,5\n");
        assert_eq!(c.width(), 3);
        assert_eq!(c.columns(["z", "x"]), Ok([2, 0]));
        assert_eq!(c.columns(["x", "w"]), Err("w"));
        let rows: Vec<Vec<&str>> = c.rows().collect();
        assert_eq!(rows, [vec!["1", "2", "3"], vec!["4", "5"]]);
        assert_eq!(field(&rows[1], 2), "");
    }
}
