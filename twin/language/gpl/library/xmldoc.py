"""XmlDoc and XmlNode (User Manual ch. 19, L3393-3731) on Python's xml.dom.minidom.

Decisions (docs/gpl.md):
* One XmlDoc per tree; an XmlNode is a handle on a node of that tree.  The same
  tree node always gives the same XmlNode object, so ``Is`` compares nodes.  A
  node removed from its tree (RemoveChild, RemoveElement, ReplaceChild) is
  freed: using its handle raises -801 "No XML node" (L3731).
* Members that return an XmlNode return Nothing when there is none; the others
  raise -799 "XML error" with a detail (L3729).  LoadString / LoadFile do not
  throw on malformed text: they return a document whose ErrorCode is -799 and
  whose Message says why (L3727).
* GPL does not escape text it is given (L3441): a value set on a node is taken
  as XML character data with its entities (``&lt;`` ...) already encoded, the
  way EncodeEntities produces it, and is stored decoded; Value returns decoded
  text.  Saving writes well-formed XML (the twin escapes ``<`` and ``&`` that a
  program left raw, where the controller would write them as they are).
* ``Type`` is a String: "element", "attribute", "text", "cdata", "comment",
  "pi" or "document"; CreateNode takes that String or libxml2's type number.
"""

from __future__ import annotations

import html
from xml.dom import Node, minidom
from xml.parsers.expat import ExpatError

from ..errors import GplError
from . import codes
from . import byref, gpl_class, shared
from .files import read_bytes, sandbox_path
from .members import stored

TYPE_NAMES = {
    Node.ELEMENT_NODE: "element", Node.ATTRIBUTE_NODE: "attribute", Node.TEXT_NODE: "text",
    Node.CDATA_SECTION_NODE: "cdata", Node.COMMENT_NODE: "comment",
    Node.PROCESSING_INSTRUCTION_NODE: "pi", Node.DOCUMENT_NODE: "document",
}
_TYPE_BY_NAME = {name: number for number, name in TYPE_NAMES.items()}


def _decode(text) -> str:
    return html.unescape(str(text))


@gpl_class("XmlDoc")
class XmlDoc:
    """An XML document (Table 19-2)."""

    def __init__(self, rt, root_name=None):
        self._rt = rt
        self._dom = minidom.Document()
        self._nodes: dict[int, XmlNode] = {}
        self._error_code = 0
        self._message = ""
        if root_name is not None:
            self._dom.appendChild(self._dom.createElement(str(root_name)))

    def node(self, dom_node) -> "XmlNode | None":
        """The one XmlNode handle of a tree node."""
        if dom_node is None:
            return None
        handle = self._nodes.get(id(dom_node))
        if handle is None:
            handle = self._nodes[id(dom_node)] = XmlNode(self, dom_node)
        return handle

    def free(self, dom_node) -> None:
        """A node left the tree: it and its descendants' handles are dead."""
        stack = [dom_node]
        while stack:
            n = stack.pop()
            handle = self._nodes.pop(id(n), None)
            if handle is not None:
                handle._dom = None
            stack.extend(n.childNodes)
            if n.attributes is not None:
                stack.extend(n.attributes.values())

    # ------------------------------------------------------------ members
    ErrorCode = stored("_error_code", readonly=True)
    Message = stored("_message", readonly=True)

    @property
    def DocumentElement(self) -> "XmlNode | None":
        return self.node(self._dom.documentElement)

    def CreateNode(self, kind, name="") -> "XmlNode":
        number = _TYPE_BY_NAME.get(str(kind).lower()) if isinstance(kind, str) else int(kind)
        dom = self._dom
        makers = {
            Node.ELEMENT_NODE: lambda: dom.createElement(str(name)),
            Node.ATTRIBUTE_NODE: lambda: dom.createAttribute(str(name)),
            Node.TEXT_NODE: lambda: dom.createTextNode(_decode(name)),
            Node.CDATA_SECTION_NODE: lambda: dom.createCDATASection(str(name)),
            Node.COMMENT_NODE: lambda: dom.createComment(str(name)),
        }
        if number not in makers:
            raise codes.fail(codes.XML_ERROR, f"CreateNode type {kind}")
        return self.node(makers[number]())

    @shared
    def EncodeEntities(rt, text) -> str:
        return html.escape(str(text), quote=True).replace("&#x27;", "&apos;")

    @shared
    def DecodeEntities(rt, text) -> str:
        return _decode(text)

    @shared
    def LoadString(rt, text, options=0) -> "XmlDoc":
        doc = XmlDoc(rt)
        try:
            doc._dom = minidom.parseString(str(text).encode("latin-1"))
        except ExpatError as err:
            doc._error_code, doc._message = codes.XML_ERROR[0], f"XML parse error: {err}"
        return doc

    @shared
    def LoadFile(rt, path, options=0) -> "XmlDoc":
        return XmlDoc.LoadString(rt, read_bytes(rt, str(path)).decode("latin-1"))

    def text(self) -> str:
        return self._dom.toxml()

    @byref(0)
    def SaveString(self, target, options=0) -> None:
        target.value = self.text()

    def SaveFile(self, path, options=0) -> None:
        """Write the document; a failure is also kept in ErrorCode / Message (E47, L3530-3548)."""
        try:
            real = sandbox_path(self._rt, str(path))
            if not real.parent.is_dir():
                raise codes.fail(codes.XML_ERROR, f"cannot write {path}: no such folder")
        except GplError as err:
            self._error_code, self._message = err.code, err.message
            raise
        real.write_text(self.text(), encoding="latin-1")
        self._error_code, self._message = 0, ""


@gpl_class("XmlNode")
class XmlNode:
    """A node of an XmlDoc tree (Table 19-3).  Made by XmlDoc, never by New."""

    def __init__(self, doc: XmlDoc, dom_node):
        if not isinstance(doc, XmlDoc):
            raise codes.fail(codes.XML_ERROR, "XmlNode objects come from an XmlDoc")
        self._doc = doc
        self._dom = dom_node

    @property
    def _n(self):
        if self._dom is None:
            raise codes.fail(codes.NO_XML_NODE)
        return self._dom

    def _wrap(self, dom_node) -> "XmlNode | None":
        return self._doc.node(dom_node)

    def _element(self):
        n = self._n
        if n.nodeType != Node.ELEMENT_NODE:
            raise codes.fail(codes.XML_ERROR, f"{TYPE_NAMES.get(n.nodeType)} node is not an element")
        return n

    def _child_element(self, name):
        for child in self._element().childNodes:
            if child.nodeType == Node.ELEMENT_NODE and child.tagName == str(name):
                return child
        return None

    # ------------------------------------------------------------ properties
    @property
    def Name(self) -> str:
        n = self._n
        if n.nodeType in (Node.ELEMENT_NODE, Node.ATTRIBUTE_NODE):
            return n.nodeName
        return TYPE_NAMES.get(n.nodeType, "")

    @property
    def Type(self) -> str:
        return TYPE_NAMES.get(self._n.nodeType, "")

    @property
    def Value(self) -> str:
        n = self._n
        if n.nodeType == Node.ELEMENT_NODE:
            return "".join(c.data for c in n.childNodes if c.nodeType in (Node.TEXT_NODE, Node.CDATA_SECTION_NODE))
        if n.nodeType == Node.ATTRIBUTE_NODE:
            return n.value
        return getattr(n, "data", "")

    @Value.setter
    def Value(self, value) -> None:
        n = self._n
        text = _decode(value)
        if n.nodeType == Node.ELEMENT_NODE:
            for child in [c for c in n.childNodes if c.nodeType in (Node.TEXT_NODE, Node.CDATA_SECTION_NODE)]:
                n.removeChild(child)
            n.appendChild(self._doc._dom.createTextNode(text))
        elif n.nodeType == Node.ATTRIBUTE_NODE:
            n.value = text
        else:
            n.data = text

    @property
    def ChildNodeCount(self) -> int:
        return len(self._n.childNodes)

    @property
    def HasChildNodes(self) -> bool:
        return self._n.hasChildNodes()

    @property
    def FirstChild(self) -> "XmlNode | None":
        return self._wrap(self._n.firstChild)

    @property
    def LastChild(self) -> "XmlNode | None":
        return self._wrap(self._n.lastChild)

    @property
    def NextSibling(self) -> "XmlNode | None":
        return self._wrap(self._n.nextSibling)

    @property
    def PreviousSibling(self) -> "XmlNode | None":
        return self._wrap(self._n.previousSibling)

    @property
    def ParentNode(self) -> "XmlNode | None":
        parent = self._n.parentNode
        return None if parent is None or parent.nodeType == Node.DOCUMENT_NODE else self._wrap(parent)

    @property
    def OwnerDocument(self) -> XmlDoc:
        return self._doc

    # ------------------------------------------------------------ attributes
    def AddAttribute(self, name, value) -> None:
        n = self._element()
        if n.hasAttribute(str(name)):
            raise codes.fail(codes.XML_ERROR, f"attribute {name} exists")
        n.setAttribute(str(name), _decode(value))

    def SetAttribute(self, name, value) -> None:
        n = self._element()
        if not n.hasAttribute(str(name)):
            raise codes.fail(codes.XML_ERROR, f"no attribute {name}")
        n.setAttribute(str(name), _decode(value))

    def GetAttribute(self, name) -> str:
        n = self._element()
        if not n.hasAttribute(str(name)):
            raise codes.fail(codes.XML_ERROR, f"no attribute {name}")
        return n.getAttribute(str(name))

    def GetAttributeNode(self, name) -> "XmlNode | None":
        return self._wrap(self._element().getAttributeNode(str(name)))

    def HasAttribute(self, name) -> bool:
        return self._element().hasAttribute(str(name))

    def RemoveAttribute(self, name) -> None:
        n = self._element()
        attribute = n.getAttributeNode(str(name))
        if attribute is None:
            raise codes.fail(codes.XML_ERROR, f"no attribute {name}")
        self._doc.free(attribute)
        n.removeAttribute(str(name))

    # ------------------------------------------------------------ elements
    def AddElementNode(self, name, value=None) -> "XmlNode":
        dom = self._doc._dom
        child = dom.createElement(str(name))
        if value is not None:
            child.appendChild(dom.createTextNode(_decode(value)))
        self._element().appendChild(child)
        return self._wrap(child)

    def AddElement(self, name, value=None) -> None:
        self.AddElementNode(name, value)

    def GetElementNode(self, name) -> "XmlNode | None":
        return self._wrap(self._child_element(name))

    def GetElement(self, name) -> str:
        child = self._child_element(name)
        if child is None:
            raise codes.fail(codes.XML_ERROR, f"no element {name}")
        return self._wrap(child).Value

    def HasElement(self, name) -> bool:
        return self._child_element(name) is not None

    def SetElement(self, name, value) -> None:
        child = self._child_element(name)
        if child is None:
            raise codes.fail(codes.XML_ERROR, f"no element {name}")
        self._wrap(child).Value = value

    def RemoveElement(self, name) -> None:
        child = self._child_element(name)
        if child is None:
            raise codes.fail(codes.XML_ERROR, f"no element {name}")
        self.RemoveChild(self._wrap(child))

    # ------------------------------------------------------------ tree edits
    def _own(self, node: "XmlNode"):
        if not isinstance(node, XmlNode) or node._doc is not self._doc:
            raise codes.fail(codes.XML_ERROR, "the node belongs to another document")
        return node._n

    def AppendChild(self, node: "XmlNode") -> None:
        """Append; a text node next to a text node merges into it (Table 19-3)."""
        n, child = self._n, self._own(node)
        last = n.lastChild
        if child.nodeType == Node.TEXT_NODE and last is not None and last.nodeType == Node.TEXT_NODE:
            last.data += child.data
            return
        n.appendChild(child)

    def InsertBefore(self, new: "XmlNode", reference: "XmlNode") -> None:
        self._n.insertBefore(self._own(new), self._own(reference))

    def InsertAfter(self, new: "XmlNode", reference: "XmlNode") -> None:
        self._n.insertBefore(self._own(new), self._own(reference).nextSibling)

    def RemoveChild(self, node: "XmlNode") -> None:
        child = self._own(node)
        if child.parentNode is not self._n:
            raise codes.fail(codes.XML_ERROR, "not a child of this node")
        self._n.removeChild(child)
        self._doc.free(child)

    def ReplaceChild(self, new: "XmlNode", old: "XmlNode") -> None:
        old_node = self._own(old)
        self._n.replaceChild(self._own(new), old_node)
        self._doc.free(old_node)

    def Clone(self, deep=False, doc=None) -> "XmlNode":
        target = doc if doc is not None else self._doc
        copy = target._dom.importNode(self._n, bool(deep))
        return target.node(copy)
