//! A small element tree built with `quick-xml` (VTK XML files are shallow and small apart
//! from their array payloads, so a tree is simpler than streaming).
use quick_xml::events::{BytesStart, Event};
use quick_xml::Reader;

/// Deepest nesting accepted (VTK files use about 6 levels).
const MAX_DEPTH: usize = 64;

/// An XML element: name, attributes, concatenated text, children.
#[derive(Clone, Debug, Default)]
pub struct Elem {
    /// Tag name.
    pub name: String,
    /// Attributes in document order.
    pub attrs: Vec<(String, String)>,
    /// Text content (unescaped), all text nodes concatenated.
    pub text: String,
    /// Child elements.
    pub children: Vec<Elem>,
}

impl Elem {
    /// The value of attribute `key`.
    pub fn attr(&self, key: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }
    /// The first child named `name`.
    pub fn child(&self, name: &str) -> Option<&Elem> {
        self.children.iter().find(|c| c.name == name)
    }
    /// The children named `name`.
    pub fn children_named<'a>(&'a self, name: &'a str) -> impl Iterator<Item = &'a Elem> + 'a {
        self.children.iter().filter(move |c| c.name == name)
    }
}

fn start(e: &BytesStart) -> Result<Elem, String> {
    let name = String::from_utf8_lossy(e.name().as_ref()).into_owned();
    let mut attrs = Vec::new();
    for a in e.attributes() {
        let a = a.map_err(|err| format!("bad attribute in <{name}>: {err}"))?;
        let k = String::from_utf8_lossy(a.key.as_ref()).into_owned();
        let v = a
            .unescape_value()
            .map_err(|err| format!("bad attribute value in <{name}>: {err}"))?;
        attrs.push((k, v.into_owned()));
    }
    Ok(Elem {
        name,
        attrs,
        ..Elem::default()
    })
}

/// Parses `xml` into a synthetic root whose children are the top-level elements. Elements
/// left open at the end of the input are closed (the caller cuts the file before its
/// `<AppendedData>` section).
pub fn parse(xml: &[u8]) -> Result<Elem, String> {
    let mut reader = Reader::from_reader(xml);
    reader.config_mut().trim_text(true);
    let mut stack = vec![Elem::default()];
    loop {
        let at = reader.buffer_position();
        let ev = reader
            .read_event()
            .map_err(|e| format!("XML error near byte {at}: {e}"))?;
        match ev {
            Event::Start(e) => {
                if stack.len() > MAX_DEPTH {
                    return Err(format!("XML nested deeper than {MAX_DEPTH} levels"));
                }
                stack.push(start(&e)?);
            }
            Event::Empty(e) => {
                let el = start(&e)?;
                if let Some(top) = stack.last_mut() {
                    top.children.push(el);
                }
            }
            Event::End(_) => close(&mut stack),
            Event::Text(t) => {
                let s = t
                    .unescape()
                    .map_err(|e| format!("bad text near byte {at}: {e}"))?;
                if let Some(top) = stack.last_mut() {
                    top.text.push_str(&s);
                }
            }
            Event::CData(t) => {
                if let Some(top) = stack.last_mut() {
                    top.text.push_str(&String::from_utf8_lossy(&t));
                }
            }
            Event::Eof => break,
            _ => {}
        }
    }
    while stack.len() > 1 {
        close(&mut stack);
    }
    stack.pop().ok_or_else(|| "empty XML".to_string())
}

fn close(stack: &mut Vec<Elem>) {
    if stack.len() > 1 {
        if let Some(el) = stack.pop() {
            if let Some(top) = stack.last_mut() {
                top.children.push(el);
            }
        }
    }
}
