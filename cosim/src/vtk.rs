//! VTK XML files that ParaView (and VisIt) open: image data (`.vti`) for fields on a grid,
//! poly data (`.vtp`) for beads, and a collection (`.pvd`) that ties each snapshot to its time.
//!
//! Binary arrays are appended raw after the XML: little-endian Float64 or Int64, each block
//! preceded by its length in bytes as a UInt64 (`header_type="UInt64"`), as the VTK XML
//! format defines it. No compression: a snapshot is written once and read by a viewer.
//! (Not the `vtkio` crate: its release depends on nom 3 and quick-xml 0.22, and the three
//! writers and the reader below are all the project needs of the format.)
use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

/// The values of one array: `components` numbers per point, point after point.
#[derive(Debug, Clone, Copy)]
pub enum Values<'a> {
    F64(&'a [f64]),
    I64(&'a [i64]),
}

impl Values<'_> {
    fn len(&self) -> usize {
        match self {
            Values::F64(v) => v.len(),
            Values::I64(v) => v.len(),
        }
    }
    fn type_name(&self) -> &'static str {
        match self {
            Values::F64(_) => "Float64",
            Values::I64(_) => "Int64",
        }
    }
    fn append_to(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&((self.len() * 8) as u64).to_le_bytes());
        match self {
            Values::F64(v) => v
                .iter()
                .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
            Values::I64(v) => v
                .iter()
                .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        }
    }
}

/// A named array of point data.
#[derive(Debug, Clone, Copy)]
pub struct Array<'a> {
    pub name: &'a str,
    /// Numbers per point (1: a scalar, 3: a vector).
    pub components: usize,
    pub values: Values<'a>,
}

impl<'a> Array<'a> {
    pub fn scalar(name: &'a str, values: &'a [f64]) -> Self {
        Self {
            name,
            components: 1,
            values: Values::F64(values),
        }
    }
    /// Three numbers per point, interleaved (x0, y0, z0, x1, ...).
    pub fn vector(name: &'a str, values: &'a [f64]) -> Self {
        Self {
            name,
            components: 3,
            values: Values::F64(values),
        }
    }
}

/// The XML of the arrays, with their offsets into the appended block that `block` collects.
struct Appended {
    xml: String,
    block: Vec<u8>,
}

impl Appended {
    fn new() -> Self {
        Self {
            xml: String::new(),
            block: Vec::new(),
        }
    }
    fn array(&mut self, a: &Array, points: usize) -> Result<(), String> {
        if a.components == 0 || a.values.len() != a.components * points {
            return Err(format!(
                "array `{}`: {} values for {points} points of {} components",
                a.name,
                a.values.len(),
                a.components
            ));
        }
        let _ = writeln!(
            self.xml,
            r#"<DataArray type="{}" Name="{}" NumberOfComponents="{}" format="appended" offset="{}"/>"#,
            a.values.type_name(),
            a.name,
            a.components,
            self.block.len()
        );
        a.values.append_to(&mut self.block);
        Ok(())
    }
    fn write(self, path: &Path, kind: &str, head: &str, body: &str) -> Result<(), String> {
        let fail = |e: std::io::Error| format!("{}: {e}", path.display());
        let mut f = std::io::BufWriter::new(std::fs::File::create(path).map_err(fail)?);
        write!(
            f,
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"{kind}\" version=\"1.0\" \
             byte_order=\"LittleEndian\" header_type=\"UInt64\">\n{head}\n{body}</{kind}>\n\
             <AppendedData encoding=\"raw\">\n_"
        )
        .map_err(fail)?;
        f.write_all(&self.block).map_err(fail)?;
        f.write_all(b"\n</AppendedData>\n</VTKFile>\n")
            .map_err(fail)?;
        f.flush().map_err(fail)
    }
}

/// Write point data on the grid of `n` nodes at integer positions (spacing 1, origin 0), x
/// fastest, then y, then z: the layout of the fluid node's fields.
pub fn write_image(path: &Path, n: [usize; 3], arrays: &[Array]) -> Result<(), String> {
    let points = n[0] * n[1] * n[2];
    let mut a = Appended::new();
    for array in arrays {
        a.array(array, points)?;
    }
    let extent = format!("0 {} 0 {} 0 {}", n[0] - 1, n[1] - 1, n[2] - 1);
    let head = format!(r#"<ImageData WholeExtent="{extent}" Origin="0 0 0" Spacing="1 1 1">"#);
    let body = format!(
        "<Piece Extent=\"{extent}\">\n<PointData>\n{}</PointData>\n</Piece>\n",
        a.xml
    );
    a.write(path, "ImageData", &head, &body)
}

/// Write points (`positions`, x, y, z each) with point data, and polylines through
/// consecutive points (`lines`: the number of points of each line, in order; a bead chain per
/// fibre).
pub fn write_points(
    path: &Path,
    positions: &[f64],
    lines: &[usize],
    arrays: &[Array],
) -> Result<(), String> {
    if !positions.len().is_multiple_of(3) || lines.iter().sum::<usize>() != positions.len() / 3 {
        return Err(format!(
            "{}: {} coordinates do not make the points of lines of {lines:?}",
            path.display(),
            positions.len()
        ));
    }
    let points = positions.len() / 3;
    let mut a = Appended::new();
    for array in arrays {
        a.array(array, points)?;
    }
    let data = std::mem::take(&mut a.xml);
    a.array(&Array::vector("Points", positions), points)?;
    let geometry = std::mem::take(&mut a.xml);
    let connectivity: Vec<i64> = (0..points as i64).collect();
    let mut offsets = Vec::with_capacity(lines.len());
    let mut end = 0;
    for &l in lines {
        end += l as i64;
        offsets.push(end);
    }
    let cell = |a: &mut Appended, offsets: &[i64]| -> Result<String, String> {
        for (name, v) in [("connectivity", &connectivity[..]), ("offsets", offsets)] {
            a.array(
                &Array {
                    name,
                    components: 1,
                    values: Values::I64(v),
                },
                v.len(),
            )?;
        }
        Ok(std::mem::take(&mut a.xml))
    };
    let verts = cell(&mut a, &(1..=points as i64).collect::<Vec<_>>())?;
    let polylines = cell(&mut a, &offsets)?;
    let body = format!(
        "<Piece NumberOfPoints=\"{points}\" NumberOfVerts=\"{points}\" NumberOfLines=\"{}\">\n\
         <PointData>\n{data}</PointData>\n<Points>\n{geometry}</Points>\n\
         <Verts>\n{verts}</Verts>\n<Lines>\n{polylines}</Lines>\n</Piece>\n",
        lines.len()
    );
    a.write(path, "PolyData", "<PolyData>", &body)
}

/// Write a collection: each entry is a time, a part number (0, 1, ... for the datasets of one
/// time) and a file relative to the collection's folder.
pub fn write_collection(path: &Path, entries: &[(f64, usize, String)]) -> Result<(), String> {
    let mut xml = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" \
         byte_order=\"LittleEndian\">\n<Collection>\n",
    );
    for (t, part, file) in entries {
        let _ = writeln!(
            xml,
            r#"<DataSet timestep="{t}" group="" part="{part}" file="{file}"/>"#
        );
    }
    xml.push_str("</Collection>\n</VTKFile>\n");
    std::fs::write(path, xml).map_err(|e| format!("{}: {e}", path.display()))
}

/// The Float64 arrays of a file written by [`write_image`] or [`write_points`], by name, in
/// file order (the integer cell arrays are skipped).
pub fn read_arrays(path: &Path) -> Result<Vec<(String, Vec<f64>)>, String> {
    let fail = |m: &str| format!("{}: {m}", path.display());
    let bytes = std::fs::read(path).map_err(|e| fail(&e.to_string()))?;
    let start = bytes
        .windows(2)
        .position(|w| w == b"\n_")
        .ok_or_else(|| fail("no appended raw data"))?
        + 2;
    let head = String::from_utf8_lossy(&bytes[..start]);
    let mut out = Vec::new();
    for line in head.lines().filter(|l| l.contains("type=\"Float64\"")) {
        let (Some(name), Some(offset)) = (
            attribute(line, "Name"),
            attribute(line, "offset").and_then(|o| o.parse::<usize>().ok()),
        ) else {
            return Err(fail("a data array without name or offset"));
        };
        let at = start + offset;
        let block = |a: usize, b: usize| bytes.get(a..b).ok_or_else(|| fail("data cut short"));
        let len = u64::from_le_bytes(block(at, at + 8)?.try_into().expect("8 bytes")) as usize;
        let values = block(at + 8, at + 8 + len)?
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
            .collect();
        out.push((name.to_string(), values));
    }
    Ok(out)
}

/// Nodes per axis of a file written by [`write_image`].
pub fn image_size(path: &Path) -> Result<[usize; 3], String> {
    let fail = |m: &str| format!("{}: {m}", path.display());
    // The header is in the first lines; the data after it may be many megabytes.
    let mut bytes = Vec::with_capacity(4096);
    std::io::Read::read_to_end(
        &mut std::io::Read::take(
            std::fs::File::open(path).map_err(|e| fail(&e.to_string()))?,
            4096,
        ),
        &mut bytes,
    )
    .map_err(|e| fail(&e.to_string()))?;
    let head = String::from_utf8_lossy(&bytes).into_owned();
    let extent = head
        .lines()
        .find_map(|l| attribute(l, "WholeExtent"))
        .ok_or_else(|| fail("no WholeExtent"))?;
    let e: Vec<usize> = extent
        .split_whitespace()
        .map(|v| {
            v.parse()
                .map_err(|_| fail("a WholeExtent that is not six integers"))
        })
        .collect::<Result<_, _>>()?;
    match e[..] {
        [0, x, 0, y, 0, z] => Ok([x + 1, y + 1, z + 1]),
        _ => Err(fail("a WholeExtent that does not start at 0")),
    }
}

/// The value of attribute `key` in one line of XML (as these files and collections are written).
pub fn attribute<'a>(line: &'a str, key: &str) -> Option<&'a str> {
    let from = line.find(&format!(" {key}=\""))? + key.len() + 3;
    line[from..].split('"').next()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The offsets in the XML point at each block's length header in the appended data, and
    /// the block holds the values little-endian.
    #[test]
    fn image_offsets_point_at_their_blocks() {
        let dir = std::env::temp_dir().join(format!("vtk-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("f.vti");
        let s = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        let v: Vec<f64> = (0..18).map(|i| i as f64).collect();
        write_image(
            &path,
            [3, 2, 1],
            &[Array::scalar("s", &s), Array::vector("v", &v)],
        )
        .unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let text = String::from_utf8_lossy(&bytes);
        assert!(text.contains(r#"WholeExtent="0 2 0 1 0 0""#));
        let start = bytes.windows(2).position(|w| w == b"\n_").unwrap() + 2;
        let read = |offset: usize| {
            let len = u64::from_le_bytes(
                bytes[start + offset..start + offset + 8]
                    .try_into()
                    .unwrap(),
            );
            let vals: Vec<f64> = bytes[start + offset + 8..start + offset + 8 + len as usize]
                .chunks(8)
                .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
                .collect();
            vals
        };
        assert!(text.contains(r#"Name="s" NumberOfComponents="1" format="appended" offset="0""#));
        assert_eq!(read(0), s);
        assert!(text.contains(r#"Name="v" NumberOfComponents="3" format="appended" offset="56""#));
        assert_eq!(read(56), v);
        let back = read_arrays(&path).unwrap();
        assert_eq!(
            back,
            [("s".to_string(), s.to_vec()), ("v".to_string(), v.clone())]
        );
        assert_eq!(image_size(&path).unwrap(), [3, 2, 1]);
        assert!(
            write_image(&path, [3, 2, 1], &[Array::scalar("short", &s[..5])])
                .unwrap_err()
                .contains("5 values for 6 points")
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
