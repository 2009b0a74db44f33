#include "basics/html_report.h"

#include "basics/csv.h"
#include "basics/files.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

namespace armsim {

namespace {

namespace fs = std::filesystem;

// Marks a page as armsim's: a later run replaces it, while an index.html of someone else is left alone.
constexpr const char* kGenerator = "<meta name=\"generator\" content=\"armsim folder report\">";

std::string escape(const std::string& s) {
    std::string out;
    for (char c : s) {
        switch (c) {
            case '&': out += "&amp;"; break;
            case '<': out += "&lt;"; break;
            case '>': out += "&gt;"; break;
            case '"': out += "&quot;"; break;
            default: out += c;
        }
    }
    return out;
}

// A path as a URL relative to the page: each segment percent-encoded where it must be.
std::string toHref(const std::string& relative) {
    static const char* kHex = "0123456789ABCDEF";
    std::string out;
    for (unsigned char c : relative) {
        if (std::isalnum(c) || c == '/' || c == '.' || c == '_' || c == '-') out += char(c);
        else out += std::string("%") + kHex[c >> 4] + kHex[c & 15];
    }
    return out;
}

std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return s;
}

// The first rows of a CSV as an HTML table (comment lines # skipped; at most 12 columns).
std::string previewCsv(const fs::path& file, int& rowsShown, long& rowsTotal) {
    std::ifstream in(file);
    std::string line, html;
    rowsShown = 0;
    rowsTotal = -1;   // the header
    std::vector<std::vector<std::string>> rows;
    while (std::getline(in, line)) {
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (line.empty() || line[0] == '#') continue;
        ++rowsTotal;
        if (int(rows.size()) > kPreviewRows) continue;
        rows.push_back(splitCsvRecord(line));
    }
    if (rows.empty()) return "";
    html += "<div class=\"table\"><table>";
    for (std::size_t r = 0; r < rows.size(); ++r) {
        html += "<tr>";
        for (std::size_t c = 0; c < rows[r].size() && c < 12; ++c) {
            std::string v = rows[r][c];
            if (r > 0) {   // numbers to 4 significant digits
                char* end = nullptr;
                const double x = std::strtod(v.c_str(), &end);
                if (!v.empty() && end && *end == '\0') {
                    std::ostringstream o;
                    o.precision(4);
                    o << x;
                    v = o.str();
                }
            }
            html += r == 0 ? "<th>" + escape(v) + "</th>" : "<td>" + escape(v) + "</td>";
        }
        html += rows[r].size() > 12 ? (r == 0 ? "<th>...</th>" : "<td>...</td>") : "";
        html += "</tr>";
    }
    html += "</table></div>";
    rowsShown = int(rows.size()) - 1;
    return html;
}

constexpr const char* kStyle = R"(body{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#222}
h1{font-size:1.6em}h2{font-size:1.25em;border-bottom:1px solid #ccc;margin-top:2em}
table{border-collapse:collapse;font-size:.85em}td,th{border:1px solid #ddd;padding:2px 6px;text-align:right}
th{background:#f3f3f3}.facts td{text-align:left}.table{overflow-x:auto;margin:.5em 0 1em}
figure{margin:1em 0}figure img,figure video{max-width:100%;border:1px solid #ddd}
figcaption,.caption{color:#444;font-size:.95em;margin:.3em 0}ul.files li{margin:.2em 0}code{font-size:.95em}
pre.printed{background:#f7f7f7;border:1px solid #ddd;padding:.5em;font-size:.8em;max-height:40em;overflow:auto})";

// On load: every image and video must have loaded; the result goes to body[data-resources].
constexpr const char* kCheck = R"(<script>
window.addEventListener('load', function () {
  var missing = [];
  document.querySelectorAll('img').forEach(function (i) {
    if (!i.complete || i.naturalWidth === 0) missing.push(i.getAttribute('src'));
  });
  var videos = Array.prototype.slice.call(document.querySelectorAll('video'));
  var pending = videos.length;
  function done() { document.body.setAttribute('data-resources', missing.length ? missing.join(' ') : 'ok'); }
  if (!pending) return done();
  videos.forEach(function (v) {
    function settle(ok) {
      if (v.dataset.settled) return;
      v.dataset.settled = '1';
      if (!ok) missing.push(v.getAttribute('src'));
      if (--pending === 0) done();
    }
    if (v.readyState >= 1) return settle(true);
    v.addEventListener('loadedmetadata', function () { settle(true); });
    v.addEventListener('error', function () { settle(false); });
    setTimeout(function () { settle(v.readyState >= 1); }, 4000);
  });
});
</script>)";

}  // namespace

bool isFolderReport(const std::string& path) {
    std::ifstream in(path);
    std::string head(512, '\0');
    in.read(head.data(), std::streamsize(head.size()));
    head.resize(std::size_t(in.gcount()));
    return head.find(kGenerator) != std::string::npos;
}

void writeFolderReport(const std::string& dir, const FolderReport& report) {
    const fs::path root(dir);
    std::error_code ec;
    if (fs::exists(root / "index.html", ec) && !isFolderReport((root / "index.html").string()))
        throw std::runtime_error((root / "index.html").string() + ": not written by armsim: left as it is");
    std::map<std::string, std::vector<std::string>> byFolder;   // folder ("" = top) -> files
    long seen = 0;
    for (fs::recursive_directory_iterator it(root, fs::directory_options::skip_permission_denied, ec), end;
         !ec && it != end; it.increment(ec)) {
        const fs::directory_entry& e = *it;
        if (++seen > kMaxReportFiles)
            throw std::runtime_error(dir + ": more than " + std::to_string(kMaxReportFiles) + " files: no report written");
        std::error_code fe;
        if (!e.is_regular_file(fe)) continue;
        const std::string rel = fs::relative(e.path(), root).generic_string();
        if (rel == "index.html" || rel.find("/.") != std::string::npos || rel[0] == '.' ||
            rel.find(".tmp") != std::string::npos)
            continue;
        const std::string folder = fs::path(rel).parent_path().generic_string();
        byFolder[folder].push_back(rel);
    }
    std::ostringstream h;
    h << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">" << kGenerator << "\n<title>" << escape(report.title)
      << "</title>\n<style>" << kStyle << "</style></head>\n<body data-resources=\"pending\">\n<h1>"
      << escape(report.title) << "</h1>\n<table class=\"facts\">";
    for (const auto& [label, value] : report.facts)
        h << "<tr><th>" << escape(label) << "</th><td><code>" << escape(value) << "</code></td></tr>";
    h << "</table>\n";
    if (!report.printed.empty())
        h << "<h2>What it printed</h2>\n<p class=\"caption\">the command's results and key numbers, as on the terminal</p>\n"
          << "<pre class=\"printed\">" << escape(report.printed) << "</pre>\n";
    for (auto& [folder, files] : byFolder) {
        std::sort(files.begin(), files.end());
        const long notShown = std::max(0L, long(files.size()) - kMaxReportFilesPerFolder);
        files.resize(files.size() - std::size_t(notShown));
        h << "<h2>" << (folder.empty() ? "Files" : escape(folder) + "/") << "</h2>\n";
        std::vector<std::string> others;
        for (const std::string& rel : files) {
            const std::string ext = lower(fs::path(rel).extension().string());
            const std::string sentence = report.describe ? report.describe(rel) : "";
            const std::string name = fs::path(rel).filename().string();
            if (ext == ".png" || ext == ".jpg") {
                h << "<figure><img src=\"" << toHref(rel) << "\" alt=\"" << escape(name) << "\" loading=\"eager\">"
                  << "<figcaption><a href=\"" << toHref(rel) << "\">" << escape(name) << "</a>"
                  << (sentence.empty() ? "" : ": " + escape(sentence)) << "</figcaption></figure>\n";
            } else if (ext == ".mp4" || ext == ".avi") {
                h << "<figure><video controls muted preload=\"metadata\" src=\"" << toHref(rel) << "\"></video>"
                  << "<figcaption><a href=\"" << toHref(rel) << "\">" << escape(name) << "</a>"
                  << (sentence.empty() ? "" : ": " + escape(sentence)) << "</figcaption></figure>\n";
            } else if (ext == ".csv") {
                int shown = 0;
                long total = 0;
                const std::string table = previewCsv(root / rel, shown, total);
                h << "<p class=\"caption\"><a href=\"" << toHref(rel) << "\">" << escape(name) << "</a>"
                  << (sentence.empty() ? "" : ": " + escape(sentence));
                if (total > shown) h << " (first " << shown << " of " << total << " rows)";
                h << "</p>\n" << table << "\n";
            } else {
                others.push_back(rel);
            }
        }
        if (!others.empty()) {
            h << "<ul class=\"files\">";
            for (const std::string& rel : others) {
                const std::string sentence = report.describe ? report.describe(rel) : "";
                h << "<li><a href=\"" << toHref(rel) << "\">" << escape(fs::path(rel).filename().string()) << "</a>"
                  << (sentence.empty() ? "" : ": " + escape(sentence)) << "</li>";
            }
            h << "</ul>\n";
        }
        if (notShown > 0)
            h << "<p class=\"caption\">and " << notShown << " more files in <a href=\"" << toHref(folder.empty() ? "." : folder)
              << "\">" << (folder.empty() ? "this folder" : escape(folder) + "/") << "</a>, not shown (the first "
              << kMaxReportFilesPerFolder << " by name are above)</p>\n";
    }
    h << kCheck << "\n</body></html>\n";
    writeFileAtomically((root / "index.html").string(), h.str());
}

}  // namespace armsim
